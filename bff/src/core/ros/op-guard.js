// Checks every rosbridge op a browser sends before it reaches rosbridge (JSON and CBOR frames), holds motion
// ops to the control lease, records commands in the audit log, and filters rosapi answers to what the role
// may use. Denied ops get a rosbridge `status` error with the op's id (and a failed `service_response` for
// calls, so roslib callbacks fire); they never reach ROS.
import { decode as cborDecode, encode as cborEncode } from 'cbor-x';
import { checkMessage, matchesAny, isFilteredRosapi, filterRosapiValues } from '../access/rules.js';

/**
 * @typedef {{username: string, role: string, sid: string}} Session
 * @typedef {{session: Session, ip: string, rosapiCalls: Map<string, string>, lastPublishAudit: Map<string, {at: number, n: number}>}} ClientCtx
 * @typedef {{data: Buffer|string, binary: boolean}} Frame
 */

const PUBLISH_AUDIT_EVERY_MS = 5000;
let injected = 0;

/**
 * @param {{grantsOf: (role: string) => import('../config/cell-types.js').RosGrants | undefined,
 *   motion: {publish: string[], call_service: string[]}, stamped?: string[], lease: import('../control/lease.js').ControlLease,
 *   audit: import('../audit/audit-log.js').AuditLog,
 *   checkArgs?: (role: string, op: string, target: string, msg: any) => string | null}} deps
 *   grantsOf: the role's grants (core/access/grants.js); motion: names whose publish or call needs the lease;
 *   checkArgs: the features' refusals by argument (core/access/grants.js argumentChecks);
 *   stamped: heartbeat topics whose messages get `stamp` = now as they pass (core/access/grants.js stampedTopics).
 */
export function createOpGuard({ grantsOf, motion, stamped = [], lease, audit, checkArgs = () => null }) {
  const stampedSet = new Set(stamped);

  /** @param {ClientCtx} ctx @param {string} op @param {string|undefined} target @param {'ok'|'denied'} outcome @param {string} [detail] */
  const record = (ctx, op, target, outcome, detail) => audit.record({
    user: ctx.session.username, role: ctx.session.role, ip: ctx.ip, op: `ros.${op}`, target, outcome, detail,
  });

  /** @param {any} msg @param {string} reason @returns {Frame[]} */
  const refusal = (msg, reason) => {
    const op = typeof msg?.op === 'string' ? msg.op : 'unknown';
    const id = typeof msg?.id === 'string' ? msg.id : undefined;
    const text = `permission denied: ${op}${id ? ` (id ${id})` : ''}: ${reason}`;
    /** @type {Frame[]} */
    const out = [{ data: JSON.stringify({ op: 'status', level: 'error', ...(id ? { id } : {}), msg: text }), binary: false }];
    if (op === 'call_service' && typeof msg.service === 'string') {
      out.push({ data: JSON.stringify({ op: 'service_response', service: msg.service, ...(id ? { id } : {}), values: text, result: false }), binary: false });
    }
    return out;
  };

  return {
    /**
     * @param {ClientCtx} ctx @param {Buffer} data @param {boolean} isBinary
     * @returns {{forward: boolean, data: Buffer, replies: Frame[], msg?: any}} msg: the decoded request when forwarded
     */
    inspect(ctx, data, isBinary) {
      let msg;
      try {
        msg = isBinary ? cborDecode(data) : JSON.parse(data.toString('utf8'));
      } catch (e) {
        return { forward: false, data, replies: refusal(null, `cannot decode the ${isBinary ? 'CBOR' : 'JSON'} frame`) };
      }
      const d = checkMessage(grantsOf(ctx.session.role), msg);
      if (!d.allow) {
        record(ctx, d.op || 'invalid', d.target, 'denied', d.reason);
        return { forward: false, data, replies: refusal(msg, d.reason) };
      }
      const { op } = msg;
      const target = d.target;
      const argsWhy = checkArgs(ctx.session.role, op, target, msg);
      if (argsWhy) {
        record(ctx, op, target, 'denied', argsWhy);
        return { forward: false, data, replies: refusal(msg, argsWhy) };
      }
      if ((op === 'publish' || op === 'call_service') && matchesAny(motion[op], target) && !lease.isHolder(ctx.session)) {
        const h = lease.describe();
        const reason = h ? `${target} needs control, which ${h.username} holds` : `${target} needs control: take control first`;
        record(ctx, op, target, 'denied', reason);
        return { forward: false, data, replies: refusal(msg, reason) };
      }
      if (op === 'publish') {
        const now = Date.now();
        const last = ctx.lastPublishAudit.get(target);
        if (!last || now - last.at >= PUBLISH_AUDIT_EVERY_MS) {
          record(ctx, op, target, 'ok', last ? `${last.n + 1} messages since the last entry` : undefined);
          ctx.lastPublishAudit.set(target, { at: now, n: 0 });
        } else last.n++;
      } else if (op === 'call_service' && !target.startsWith('/rosapi/')) record(ctx, op, target, 'ok');
      else if (op === 'advertise' || op === 'advertise_service') record(ctx, op, target, 'ok');

      if (op === 'publish' && stampedSet.has(target) && msg.msg && typeof msg.msg === 'object' && !Array.isArray(msg.msg)) {
        // When it was let through: the driver drops a heartbeat that arrives later than its jog timeout.
        const now = Date.now();
        const clean = { ...msg, msg: { ...msg.msg, stamp: { secs: Math.floor(now / 1000), nsecs: (now % 1000) * 1e6 } } };
        return { forward: true, data: isBinary ? Buffer.from(cborEncode(clean)) : Buffer.from(JSON.stringify(clean)), replies: [], msg: clean };
      }
      if (op === 'call_service' && isFilteredRosapi(target)) {
        // The answer must be matched to this call to be filtered: give it an id and keep it in one plain frame.
        const id = typeof msg.id === 'string' ? msg.id : `bff_rosapi_${++injected}`;
        const changed = id !== msg.id || msg.fragment_size !== undefined || (msg.compression && msg.compression !== 'none' && msg.compression !== 'cbor');
        ctx.rosapiCalls.set(id, target);
        if (changed) {
          const clean = { ...msg, id };
          delete clean.fragment_size;
          if (clean.compression !== 'cbor') delete clean.compression;
          return { forward: true, data: isBinary ? Buffer.from(cborEncode(clean)) : Buffer.from(JSON.stringify(clean)), replies: [], msg: clean };
        }
      }
      return { forward: true, data, replies: [], msg };
    },

    /** Frames from rosbridge to this browser. @param {ClientCtx} ctx @param {Buffer} data @param {boolean} isBinary @returns {Buffer} */
    outbound(ctx, data, isBinary) {
      if (ctx.rosapiCalls.size === 0) return data;
      if (!isBinary && !data.includes('"service_response"')) return data;
      let msg;
      try {
        msg = isBinary ? cborDecode(data) : JSON.parse(data.toString('utf8'));
      } catch {
        return data;
      }
      if (msg?.op !== 'service_response' || !ctx.rosapiCalls.has(msg.id)) return data;
      const service = /** @type {string} */ (ctx.rosapiCalls.get(msg.id));
      ctx.rosapiCalls.delete(msg.id);
      if (!msg.result) return data;
      const out = { ...msg, values: filterRosapiValues(grantsOf(ctx.session.role), service, msg.values) };
      if (typeof out.id === 'string' && out.id.startsWith('bff_rosapi_')) delete out.id;
      return isBinary ? Buffer.from(cborEncode(out)) : Buffer.from(JSON.stringify(out));
    },
  };
}
