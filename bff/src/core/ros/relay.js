// The /ros WebSocket: authenticated by the session cookie, one upstream rosbridge socket per browser socket.
// Transport only: what may pass is decided by the guard (ros/op-guard.js).
import { WebSocketServer, WebSocket } from 'ws';

/**
 * @typedef {import('./op-guard.js').Session & {claims: import('../auth/tokens.js').Claims}} Session
 * @typedef {import('./op-guard.js').ClientCtx} ClientCtx
 * @typedef {{inspect: (ctx: ClientCtx, data: Buffer, isBinary: boolean) => {forward: boolean, data: Buffer, replies: import('./op-guard.js').Frame[]},
 *   outbound: (ctx: ClientCtx, data: Buffer, isBinary: boolean) => Buffer}} Guard
 */

export class RosRelay {
  /**
   * @param {{upstreamUrl: string, authenticate: (req: import('node:http').IncomingMessage) => Session|null,
   *   checkOrigin?: (req: import('node:http').IncomingMessage) => boolean, guard: Guard,
   *   isValid?: (s: Session) => boolean, onClose?: (s: Session, stillOpen: number) => void,
   *   recheckMs?: number, log?: (msg: string) => void}} o
   */
  constructor({ upstreamUrl, authenticate, checkOrigin = () => true, guard, isValid = () => true,
    onClose = () => {}, recheckMs = 1000, log = () => {} }) {
    this.upstreamUrl = upstreamUrl;
    this.authenticate = authenticate;
    this.checkOrigin = checkOrigin;
    this.guard = guard;
    this.isValid = isValid;
    this.onClose = onClose;
    this.log = log;
    this.wss = new WebSocketServer({ noServer: true, maxPayload: 16 * 1024 * 1024 });
    /** @type {Map<WebSocket, ClientCtx & {session: Session}>} */
    this.clients = new Map();
    // Sessions are re-checked so an expired or revoked login, or a removed user, loses its socket.
    this.timer = setInterval(() => this.recheck(), recheckMs);
    this.timer.unref();
  }

  /**
   * The browser's socket opens only once rosbridge answers, so "connected" in the app means connected to ROS;
   * with rosbridge down the upgrade is refused with 502 and the app retries with backoff.
   * @param {import('node:http').IncomingMessage} req @param {import('node:stream').Duplex} socket @param {Buffer} head
   */
  handleUpgrade(req, socket, head) {
    if (!this.checkOrigin(req)) return refuse(socket, 403, 'Forbidden');
    const session = this.authenticate(req);
    if (!session) return refuse(socket, 401, 'Unauthorized');
    const up = new WebSocket(this.upstreamUrl, { perMessageDeflate: false, maxPayload: 64 * 1024 * 1024 });
    /** @type {[Buffer, boolean][]} */
    const early = [];
    const onEarly = (d, b) => early.push([d, b]);
    up.on('message', onEarly);
    up.once('error', (e) => {
      this.log(`rosbridge unavailable for ${session.username}: ${e.message}`);
      refuse(socket, 502, 'Bad Gateway');
    });
    socket.once('close', () => { if (up.readyState === WebSocket.CONNECTING) up.terminate(); });
    up.once('open', () => {
      if (socket.destroyed) { up.close(); return; }
      this.wss.handleUpgrade(req, socket, head, (ws) => {
        up.off('message', onEarly);
        this.bridge(ws, up, session, req);
        for (const [d, b] of early) ws.send(d, { binary: b });
      });
    });
  }

  /** @param {WebSocket} ws @param {WebSocket} up @param {Session} session @param {import('node:http').IncomingMessage} req */
  bridge(ws, up, session, req) {
    /** @type {ClientCtx & {session: Session}} */
    const ctx = { session, ip: req.socket.remoteAddress || '', rosapiCalls: new Map(), lastPublishAudit: new Map() };
    this.clients.set(ws, ctx);
    up.removeAllListeners('error');
    let closed = false;
    const closeBoth = (code, reason) => {
      if (!closed) {
        closed = true;
        this.clients.delete(ws);
        this.onClose(session, [...this.clients.values()].filter((c) => c.session.sid === session.sid).length);
      }
      if (ws.readyState === WebSocket.OPEN || ws.readyState === WebSocket.CONNECTING) ws.close(code, reason);
      if (up.readyState === WebSocket.OPEN) up.close();
      else if (up.readyState === WebSocket.CONNECTING) up.terminate();
    };
    up.on('message', (data, isBinary) => {
      if (ws.readyState !== WebSocket.OPEN) return;
      ws.send(this.guard.outbound(ctx, /** @type {Buffer} */ (data), isBinary), { binary: isBinary });
    });
    up.on('close', () => closeBoth(1012, 'rosbridge closed'));
    up.on('error', (e) => {
      this.log(`rosbridge upstream error for ${session.username}: ${e.message}`);
      closeBoth(1011, 'rosbridge error');
    });
    ws.on('message', (raw, isBinary) => {
      const data = Array.isArray(raw) ? Buffer.concat(raw) : Buffer.from(/** @type {any} */ (raw));
      const v = this.guard.inspect(ctx, data, isBinary);
      if (ws.readyState === WebSocket.OPEN) for (const r of v.replies) ws.send(r.data, { binary: r.binary });
      if (v.forward && up.readyState === WebSocket.OPEN) up.send(v.data, { binary: isBinary });
    });
    ws.on('close', () => closeBoth(1000, ''));
    ws.on('error', () => closeBoth(1011, ''));
    this.log(`/ros opened by ${session.username} (${session.role}) from ${ctx.ip}`);
  }

  recheck() {
    for (const [ws, c] of this.clients) if (!this.isValid(c.session)) this.drop(ws, 'session ended');
  }

  /** Close every socket matching (a logout, a removed user). @param {(s: Session) => boolean} pred @param {string} reason */
  closeWhere(pred, reason) {
    for (const [ws, c] of this.clients) if (pred(c.session)) this.drop(ws, reason);
  }

  /** @param {WebSocket} ws @param {string} reason */
  drop(ws, reason) {
    this.log(`closing /ros of ${this.clients.get(ws)?.session.username}: ${reason}`);
    ws.close(4001, reason);
  }

  close() {
    clearInterval(this.timer);
    for (const ws of this.clients.keys()) ws.terminate();
    this.wss.close();
  }
}

/** @param {import('node:stream').Duplex} socket @param {number} code @param {string} text */
function refuse(socket, code, text) {
  socket.end(`HTTP/1.1 ${code} ${text}\r\nConnection: close\r\nContent-Length: 0\r\n\r\n`);
}
