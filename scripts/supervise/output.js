// The supervisor's own output (its stdout and stderr), written without ever blocking it.
//
// Node writes process.stdout to a pipe synchronously on Linux: a reader that stops reading (a stuck log
// collector, a paused terminal, a test harness busy elsewhere) would freeze the supervisor, then every child
// whose output it relays, the BFF included, and finally Ctrl-C itself. Here each line goes into a bounded queue
// that one write at a time drains without blocking (fdOutput); when the queue is full, lines are dropped and
// counted, and the count is reported once the reader keeps up again.
import fs from 'node:fs';
import net from 'node:net';

/** @typedef {(buf: Buffer, done: (err: NodeJS.ErrnoException | null, written?: number) => void) => void} WriteFn */

export class LineOutput {
  /**
   * @param {WriteFn} write one write to the stream; calls back with the bytes written
   * @param {{maxBytes?: number, onError?: (e: NodeJS.ErrnoException) => void}} [opts]
   *   maxBytes: queued bytes beyond which lines are dropped; onError: the stream failed (its reader is gone)
   */
  constructor(write, { maxBytes = 1 << 20, onError = () => {} } = {}) {
    this.writeFn = write;
    this.maxBytes = maxBytes;
    this.onError = onError;
    /** @type {Buffer[]} */
    this.queue = [];
    this.queuedBytes = 0;
    this.busy = false;
    this.failed = false;
    /** Lines dropped since the last report. */
    this.dropped = 0;
    /** Lines dropped in all. */
    this.droppedTotal = 0;
    /** @type {Set<() => void>} */
    this.idleWaiters = new Set();
  }

  /** Queue one line (a newline is added); dropped and counted when the queue is full. @param {string} text */
  line(text) {
    if (this.failed) return;
    const buf = Buffer.from(`${text}\n`);
    if (this.queuedBytes + buf.length > this.maxBytes) {
      this.dropped++;
      this.droppedTotal++;
      return;
    }
    this.queue.push(buf);
    this.queuedBytes += buf.length;
    this.pump();
  }

  /** True when nothing is queued or being written. */
  get idle() { return !this.busy && this.queue.length === 0; }

  /** Wait until everything queued is written, at most `ms`; true if it was. @param {number} ms */
  flush(ms) {
    if (this.idle || this.failed) return Promise.resolve(this.idle);
    return new Promise((resolve) => {
      const done = () => { clearTimeout(t); this.idleWaiters.delete(done); resolve(this.idle); };
      const t = setTimeout(done, ms);
      this.idleWaiters.add(done);
    });
  }

  /** @private */
  pump() {
    if (this.busy || this.failed) return;
    if (this.queue.length === 0 && this.dropped > 0) {
      // The reader caught up: say what it missed before anything newer.
      const n = this.dropped;
      this.dropped = 0;
      const notice = Buffer.from(`[stack] ${n} line${n === 1 ? '' : 's'} of output dropped: whatever reads this output did not keep up\n`);
      this.queue.push(notice);
      this.queuedBytes += notice.length;
    }
    if (this.queue.length === 0) {
      for (const w of [...this.idleWaiters]) w();
      return;
    }
    const buf = this.queue.length === 1 ? this.queue[0] : Buffer.concat(this.queue);
    this.queue = [];
    this.busy = true;
    this.writeFn(buf, (err, written = 0) => {
      this.busy = false;
      if (err && err.code === 'EAGAIN') written = 0; // a non-blocking pipe that is full: try again shortly
      else if (err) {
        this.failed = true;
        this.queue = [];
        this.queuedBytes = 0;
        for (const w of [...this.idleWaiters]) w();
        this.onError(err);
        return;
      }
      this.queuedBytes -= written;
      if (written < buf.length) this.queue.unshift(buf.subarray(written));
      if (err) setTimeout(() => this.pump(), 50).unref();
      else this.pump();
    });
  }
}

/**
 * The stack's stdout or stderr as a LineOutput. A pipe or socket is opened as a libuv stream, which puts it in
 * non-blocking mode: a write to a full pipe waits in the event loop, not in a thread. (fs.write would block a
 * thread-pool thread, and at exit Node waits for that thread for ever.) A file or terminal: fs.write.
 * @param {number} fd @param {{maxBytes?: number, onError?: (e: NodeJS.ErrnoException) => void}} [opts]
 */
export function fdOutput(fd, opts) {
  let stat = null;
  try { stat = fs.fstatSync(fd); } catch { /* closed: every write fails and is reported */ }
  if (stat && (stat.isFIFO() || stat.isSocket())) {
    const sock = new net.Socket({ fd, readable: false, writable: true });
    sock.on('error', () => { /* reported to the write's callback */ });
    sock.unref(); // a pending write never keeps the process alive
    return new LineOutput((buf, done) => {
      sock.write(buf, (err) => done(/** @type {NodeJS.ErrnoException | null} */ (err ?? null), err ? 0 : buf.length));
    }, opts);
  }
  return new LineOutput((buf, done) => fs.write(fd, buf, 0, buf.length, null, done), opts);
}
