/**
 * System's plain logic: health rows and uptime text, and the expected refresh period of its values. Texts come from
 * messages/system, numbers in the user's locale.
 */
import { m } from '$lib/paraglide/messages.js';
import { fmtNumber } from '$lib/core/i18n.js';

/** /api/system is polled this often; its values are stale after two missed polls. */
export const POLL_MS = 3000;
export const STALE_AFTER_MS = 2 * POLL_MS + 1000;

/** @param {number} s */
export function uptimeText(s) {
  if (!Number.isFinite(s)) return '—';
  const n = (/** @type {number} */ v) => fmtNumber(v);
  const d = Math.floor(s / 86400), h = Math.floor((s % 86400) / 3600), min = Math.floor((s % 3600) / 60);
  return d ? `${n(d)} d ${n(h)} h` : h ? `${n(h)} h ${n(min)} min` : `${n(min)} min ${n(Math.floor(s % 60))} s`;
}

/** The BFF's status word ('ok') in the user's language; another word as it is. @param {string} status */
function statusText(status) {
  return status === 'ok' ? m.system_status_ok() : String(status ?? '');
}

/**
 * The plant broker link's state in the user's language ('down' with its error).
 * @param {PlantLink} link
 */
function linkText(link) {
  switch (link.state) {
    case 'connected': return m.system_link_connected();
    case 'connecting': return m.system_link_connecting();
    case 'down': return link.error ? m.system_link_down_error({ error: link.error }) : m.system_link_down();
    default: return String(link.state ?? '');
  }
}

/**
 * @typedef {{ state: string, since: number, error: string }} PlantLink
 * @typedef {{ status: string, ros?: { rosbridge?: boolean, master?: boolean }, uptime_s: number, version: string,
 *   plant?: { broker: string, group_id: string, edge_node_id: string, reporting: PlantLink, view: PlantLink } }} Health
 * @param {Health | null | undefined} health
 * @param {boolean} offline  the BFF did not answer the last poll
 * @returns {{ label: string, ok: boolean, text: string }[]}
 */
export function healthRows(health, offline) {
  if (!health) return [];
  return [
    { label: 'BFF', ok: !offline && health.status === 'ok', text: offline ? m.system_link_unreachable() : statusText(health.status) },
    { label: 'rosbridge', ok: !!health.ros?.rosbridge, text: health.ros?.rosbridge ? m.system_link_up() : m.system_link_down() },
    { label: m.system_ros_master(), ok: !!health.ros?.master, text: health.ros?.master ? m.system_link_up() : m.system_link_down() },
    // The plant's broker (cell files with a plant section): this cell's report on it.
    ...(health.plant && health.plant.reporting.state !== 'off' ? [{
      label: m.system_plant_broker({ broker: health.plant.broker }), ok: health.plant.reporting.state === 'connected',
      text: linkText(health.plant.reporting),
    }] : []),
  ];
}
