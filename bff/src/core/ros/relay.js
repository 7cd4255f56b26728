// The /ros WebSocket: authenticated by the session cookie, one upstream rosbridge socket per browser socket.
// Transport only: what may pass is decided by the guard (ros/op-guard.js); what waits for a slow browser, and
// what may be dropped, by the outbox (ros/outbox.js). Each browser has its own outbox and send window, so a
// slow or sleeping phone never holds up another socket; rosbridge's socket is always read.
import { WebSocketServer, WebSocket } from 'ws';
import { ClientOutbox, SendWindow, DEFAULTS as FLOW_DEFAULTS } from './outbox.js';

/**
 * @typedef {import('./op-guard.js').Session & {claims: import('../auth/tokens.js').Claims}} Session
 * @typedef {import('./op-guard.js').ClientCtx} ClientCtx
 * @typedef {{inspect: (ctx: ClientCtx, data: Buffer, isBinary: boolean) => {forward: boolean, data: Buffer, replies: import('./op-guard.js').Frame[], msg?: any},
 *   outbound: (ctx: ClientCtx, data: Buffer, isBinary: boolean) => Buffer}} Guard
 */

export class RosRelay {
  /**
   * @param {{upstreamUrl: string, authenticate: (req: import('node:http').IncomingMessage) => Session|null,
   *   checkOrigin?: (req: import('node:http').IncomingMessage) => boolean, guard: Guard,
   *   isValid?: (s: Session) => boolean, onClose?: (s: Session, stillOpen: number) => void,
   *   recheckMs?: number, log?: (msg: string) => void, flow?: Partial<typeof FLOW_DEFAULTS>}} o
   *   flow: per-client queue bounds and send window (ros/outbox.js DEFAULTS).
   */
  constructor({ upstreamUrl, authenticate, checkOrigin = () => true, guard, isValid = () => true,
    onClose = () => {}, recheckMs = 1000, log = () => {}, flow = {} }) {
    this.flow = { ...FLOW_DEFAULTS, ...flow };
    this.upstreamUrl = upstreamUrl;
    this.authenticate = authenticate;
    this.checkOrigin = checkOrigin;
    this.guard = guard;
    this.isValid = isValid;
    this.onClose = onClose;
    this.log = log;
    this.wss = new WebSocketServer({ noServer: true, maxPayload: 16 * 1024 * 1024 });
    /** @type {Map<WebSocket, ClientCtx & {session: Session, outbox: ClientOutbox, window: SendWindow}>} */
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
        const out = this.bridge(ws, up, session, req);
        for (const [d, b] of early) out(d, b);
      });
    });
  }

  /**
   * @param {WebSocket} ws @param {WebSocket} up @param {Session} session @param {import('node:http').IncomingMessage} req
   * @returns {(data: Buffer, isBinary: boolean) => void} queues a frame from rosbridge for this browser
   */
  bridge(ws, up, session, req) {
    const outbox = new ClientOutbox(this.flow);
    const window = new SendWindow(this.flow);
    /** @type {ClientCtx & {session: Session, outbox: ClientOutbox, window: SendWindow}} */
    const ctx = { session, ip: req.socket.remoteAddress || '', rosapiCalls: new Map(), lastPublishAudit: new Map(), outbox, window };
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

    // Write while the browser has confirmed reading all but windowBytes (pong) and ws holds little unsent.
    // Frames and pings written in one go leave in one write (ws's socket is corked around them).
    const socket = /** @type {import('node:net').Socket} */ (/** @type {any} */ (ws)._socket);
    const pump = () => {
      socket.cork();
      try {
        while (ws.readyState === WebSocket.OPEN && window.open() && ws.bufferedAmount < window.windowBytes) {
          const f = outbox.shift();
          if (!f) return;
          ws.send(f.data, { binary: f.binary }, afterWrite);
          const ping = window.wrote(f.data.length);
          if (ping) ws.ping(ping);
        }
      } finally { socket.uncork(); }
    };
    const afterWrite = () => { if (outbox.length) pump(); };
    ws.on('pong', (d) => { if (window.pong(d.toString('latin1')) && outbox.length) pump(); });
    // The link's own round trip, before any frame is in flight: what the send window grows from.
    ws.ping(window.probe());
    /** @param {Buffer|string} data @param {boolean} isBinary */
    const out = (data, isBinary) => {
      if (closed || ws.readyState !== WebSocket.OPEN) return;
      if (!outbox.push(typeof data === 'string' ? Buffer.from(data) : data, isBinary)) {
        this.log(`closing /ros of ${session.username}: not reading (${outbox.replyBytes} bytes of replies unsent, limit ${outbox.maxReplyBytes})`);
        ws.terminate();
        closeBoth(1008, 'client too slow');
        return;
      }
      pump();
    };

    up.on('message', (data, isBinary) => out(this.guard.outbound(ctx, /** @type {Buffer} */ (data), isBinary), isBinary));
    up.on('close', () => closeBoth(1012, 'rosbridge closed'));
    up.on('error', (e) => {
      this.log(`rosbridge upstream error for ${session.username}: ${e.message}`);
      closeBoth(1011, 'rosbridge error');
    });
    ws.on('message', (raw, isBinary) => {
      const data = Array.isArray(raw) ? Buffer.concat(raw) : Buffer.from(/** @type {any} */ (raw));
      const v = this.guard.inspect(ctx, data, isBinary);
      for (const r of v.replies) out(typeof r.data === 'string' ? Buffer.from(r.data) : r.data, r.binary);
      if (v.forward && up.readyState === WebSocket.OPEN) {
        outbox.noteRequest(v.msg);
        up.send(v.data, { binary: isBinary });
      }
    });
    ws.on('close', () => closeBoth(1000, ''));
    ws.on('error', () => closeBoth(1011, ''));
    this.log(`/ros opened by ${session.username} (${session.role}) from ${ctx.ip}`);
    return out;
  }

  /** Queue counters of every open /ros socket (tests, benchmarks). */
  flowStats() {
    return [...this.clients.values()].map(({ session, outbox, window }) => ({
      username: session.username, queuedBytes: outbox.queuedBytes, peakQueuedBytes: outbox.peakQueuedBytes,
      replyBytes: outbox.replyBytes, dropped: outbox.dropped, droppedBytes: outbox.droppedBytes,
      sentBytes: window.sentBytes, unacked: window.unacked, windowBytes: window.windowBytes, minRttMs: window.minRttMs,
    }));
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
