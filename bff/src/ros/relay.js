// The /ros WebSocket: authenticated by the session cookie, one upstream rosbridge socket per browser socket.
// Frames pass through `inspect` (the access rules) before they reach rosbridge.
import { WebSocketServer, WebSocket } from 'ws';

/**
 * @typedef {{username: string, role: string, claims: {jti: string, exp: number}}} Session
 * @typedef {(session: Session, data: Buffer, isBinary: boolean) => {forward: boolean, reply?: string}} Inspector
 */

/** Everything passes; the access-rules issue replaces this. */
export const allowAll = () => ({ forward: true });

export class RosRelay {
  /**
   * @param {{upstreamUrl: string, authenticate: (req: import('node:http').IncomingMessage) => Session|null,
   *   checkOrigin?: (req: import('node:http').IncomingMessage) => boolean, inspect?: Inspector,
   *   isValid?: (s: Session) => boolean, recheckMs?: number, log?: (msg: string) => void}} o
   */
  constructor({ upstreamUrl, authenticate, checkOrigin = () => true, inspect = allowAll, isValid = () => true, recheckMs = 2000, log = () => {} }) {
    this.isValid = isValid;
    this.upstreamUrl = upstreamUrl;
    this.authenticate = authenticate;
    this.checkOrigin = checkOrigin;
    this.inspect = inspect;
    this.log = log;
    this.wss = new WebSocketServer({ noServer: true, maxPayload: 16 * 1024 * 1024 });
    /** @type {Map<WebSocket, Session>} */
    this.clients = new Map();
    // Sessions are re-checked so an expired token, a revoked one or a removed user loses its socket.
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
    this.clients.set(ws, session);
    up.removeAllListeners('error');
    const closeBoth = (code, reason) => {
      this.clients.delete(ws);
      if (ws.readyState === WebSocket.OPEN || ws.readyState === WebSocket.CONNECTING) ws.close(code, reason);
      if (up.readyState === WebSocket.OPEN) up.close();
      else if (up.readyState === WebSocket.CONNECTING) up.terminate();
    };
    up.on('message', (data, isBinary) => {
      if (ws.readyState === WebSocket.OPEN) ws.send(data, { binary: isBinary });
    });
    up.on('close', () => closeBoth(1012, 'rosbridge closed'));
    up.on('error', (e) => {
      this.log(`rosbridge upstream error for ${session.username}: ${e.message}`);
      closeBoth(1011, 'rosbridge error');
    });
    ws.on('message', (raw, isBinary) => {
      const data = /** @type {Buffer} */ (Array.isArray(raw) ? Buffer.concat(raw) : Buffer.from(/** @type {any} */ (raw)));
      const verdict = this.inspect(session, data, isBinary);
      if (verdict.reply && ws.readyState === WebSocket.OPEN) ws.send(verdict.reply);
      if (verdict.forward && up.readyState === WebSocket.OPEN) up.send(data, { binary: isBinary });
    });
    ws.on('close', () => closeBoth(1000, ''));
    ws.on('error', () => closeBoth(1011, ''));
    this.log(`/ros opened by ${session.username} (${session.role}) from ${req.socket.remoteAddress}`);
  }

  recheck() {
    for (const [ws, s] of this.clients) {
      if (s.claims.exp * 1000 <= Date.now()) this.drop(ws, 'session expired');
      else if (!this.isValid(s)) this.drop(ws, 'session no longer valid');
    }
  }

  /** Close every socket of a session (logout) or of a user (removed). @param {(s: Session) => boolean} pred @param {string} reason */
  closeWhere(pred, reason) {
    for (const [ws, s] of this.clients) if (pred(s)) this.drop(ws, reason);
  }

  /** @param {WebSocket} ws @param {string} reason */
  drop(ws, reason) {
    this.clients.delete(ws);
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
