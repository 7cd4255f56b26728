// Is ROS there? The rosbridge port answers a TCP connect; the master answers XML-RPC getPid.
import net from 'node:net';
import http from 'node:http';

/** @param {string} host @param {number} port @param {number} timeoutMs */
export function tcpReachable(host, port, timeoutMs = 500) {
  return new Promise((resolve) => {
    const s = net.connect({ host, port });
    const done = (ok) => { s.destroy(); resolve(ok); };
    s.setTimeout(timeoutMs, () => done(false));
    s.once('connect', () => done(true));
    s.once('error', () => done(false));
  });
}

/** @param {string} masterUri @param {number} timeoutMs */
export function masterOnline(masterUri, timeoutMs = 500) {
  const body = '<?xml version="1.0"?><methodCall><methodName>getPid</methodName><params><param><value><string>/cell_bff</string></value></param></params></methodCall>';
  return new Promise((resolve) => {
    let url;
    try { url = new URL(masterUri); } catch { resolve(false); return; }
    const req = http.request({ host: url.hostname, port: url.port || 11311, path: '/', method: 'POST', timeout: timeoutMs,
      headers: { 'content-type': 'text/xml', 'content-length': Buffer.byteLength(body) } }, (res) => {
      res.resume();
      resolve(res.statusCode === 200);
    });
    req.on('timeout', () => { req.destroy(); resolve(false); });
    req.on('error', () => resolve(false));
    req.end(body);
  });
}

/** Health of the ROS side, cached briefly so a busy UI does not hammer the master. */
export class RosHealth {
  /** @param {{masterUri: string, rosbridgePort: number}} o */
  constructor({ masterUri, rosbridgePort }) {
    this.masterUri = masterUri;
    this.rosbridgePort = rosbridgePort;
    this.last = null;
    this.at = 0;
  }
  /** @returns {Promise<{master: boolean, rosbridge: boolean}>} */
  async get() {
    if (this.last && Date.now() - this.at < 1000) return this.last;
    const [master, rosbridge] = await Promise.all([
      masterOnline(this.masterUri), tcpReachable('127.0.0.1', this.rosbridgePort),
    ]);
    this.last = { master, rosbridge };
    this.at = Date.now();
    return this.last;
  }
}
