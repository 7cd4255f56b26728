// The plant reporter's own read-only link to the cell's rosbridge (not a user's session: it subscribes, nothing
// else). It reconnects with back-off; while it is down the report says so.
import WebSocket from 'ws';

export class RosReader {
  /**
   * @param {object} o
   * @param {string} o.url ws://127.0.0.1:<rosbridge port>
   * @param {{topic: string, type: string}[]} o.topics
   * @param {(topic: string, msg: any) => void} o.onMessage
   * @param {(up: boolean) => void} o.onLink
   * @param {(m: string) => void} [o.log]
   */
  constructor({ url, topics, onMessage, onLink, log = () => {} }) {
    this.url = url;
    this.topics = topics;
    this.onMessage = onMessage;
    this.onLink = onLink;
    this.log = log;
    /** @type {WebSocket | null} */
    this.ws = null;
    this.delayMs = 500;
    this.closed = false;
    /** @type {NodeJS.Timeout | null} */
    this.timer = null;
    this.up = false;
  }

  start() {
    if (this.closed) return;
    const ws = new WebSocket(this.url);
    this.ws = ws;
    ws.on('open', () => {
      this.delayMs = 500;
      for (const { topic, type } of this.topics) {
        // Robot states come at 20 Hz: 5 a second are plenty for a plant view (alarms and the mode are latched).
        const throttle = topic.startsWith('/cell/manual/') ? 200 : 0;
        ws.send(JSON.stringify({ op: 'subscribe', id: `plant:${topic}`, topic, type, throttle_rate: throttle, queue_length: 1 }));
      }
      this.setUp(true);
    });
    ws.on('message', (data) => {
      let m;
      try { m = JSON.parse(data.toString()); } catch { return; }
      if (m?.op === 'publish' && typeof m.topic === 'string') this.onMessage(m.topic, m.msg);
    });
    ws.on('error', () => {}); // 'close' follows
    ws.on('close', () => {
      this.ws = null;
      this.setUp(false);
      if (this.closed) return;
      this.timer = setTimeout(() => this.start(), this.delayMs);
      this.delayMs = Math.min(this.delayMs * 2, 5000);
    });
  }

  /** @param {boolean} up */
  setUp(up) {
    if (up === this.up) return;
    this.up = up;
    this.log(`plant: the ROS link is ${up ? 'up' : 'down'}`);
    this.onLink(up);
  }

  close() {
    this.closed = true;
    if (this.timer) clearTimeout(this.timer);
    this.ws?.terminate();
  }
}
