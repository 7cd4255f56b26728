// The supervisor's output (scripts/supervise/output.js): a reader that stops reading never blocks the writer;
// lines beyond the bound are dropped and counted, and the count is reported once the reader keeps up.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { LineOutput } from '../supervise/output.js';

/** A stream whose writes complete only when the test says so. */
function heldStream() {
  /** @type {{buf: Buffer, done: (err: any, n?: number) => void}[]} */
  const pending = [];
  let text = '';
  const stream = {
    pending,
    text: () => text,
    write: (/** @type {Buffer} */ buf, /** @type {(err: any, n?: number) => void} */ done) => { pending.push({ buf, done }); },
    /** Complete the oldest write in full. */
    complete() {
      const w = pending.shift();
      if (!w) return false;
      text += w.buf.toString();
      w.done(null, w.buf.length);
      return true;
    },
    drain() { while (stream.complete()); },
  };
  return stream;
}

test('a stalled reader: lines queue up to the bound, the rest are dropped and counted, then reported in order', () => {
  const s = heldStream();
  const out = new LineOutput(s.write, { maxBytes: 100 });
  out.line('first');            // written at once (in flight)
  for (let i = 0; i < 30; i++) out.line(`line ${String(i).padStart(2, '0')}`); // 8 bytes each: 12 fit in 100
  assert.equal(s.pending.length, 1, 'one write at a time');
  assert.equal(out.droppedTotal, 30 - 11, 'the 19 lines beyond the bound are dropped');
  s.drain();
  out.line('after');
  s.drain();
  const lines = s.text().trim().split('\n');
  assert.equal(lines[0], 'first');
  assert.deepEqual(lines.slice(1, 12), Array.from({ length: 11 }, (_, i) => `line ${String(i).padStart(2, '0')}`));
  assert.equal(lines[12], '[stack] 19 lines of output dropped: whatever reads this output did not keep up');
  assert.equal(lines[13], 'after');
  assert.equal(lines.length, 14);
  assert.equal(out.dropped, 0, 'reported once');
});

test('partial writes are continued where they stopped', () => {
  let text = '';
  const out = new LineOutput((buf, done) => {
    const n = Math.min(3, buf.length);
    text += buf.subarray(0, n).toString();
    setImmediate(() => done(null, n));
  });
  out.line('hello world');
  out.line('second line');
  return out.flush(1000).then((idle) => {
    assert.equal(idle, true);
    assert.equal(text, 'hello world\nsecond line\n');
  });
});

test('EAGAIN (a full non-blocking pipe) is retried, not lost', async () => {
  let calls = 0;
  let text = '';
  const out = new LineOutput((buf, done) => {
    calls++;
    if (calls <= 2) { const e = /** @type {NodeJS.ErrnoException} */ (new Error('EAGAIN')); e.code = 'EAGAIN'; done(e); return; }
    text += buf.toString();
    done(null, buf.length);
  });
  out.line('kept');
  assert.equal(await out.flush(2000), true);
  assert.equal(text, 'kept\n');
  assert.equal(calls, 3);
});

test('a reader that is gone (EPIPE) is reported once; later lines are ignored and flush does not wait', async () => {
  /** @type {string[]} */
  const errors = [];
  const s = heldStream();
  const out = new LineOutput(s.write, { onError: (e) => errors.push(String(e.code)) });
  out.line('one');
  out.line('two');
  const e = /** @type {NodeJS.ErrnoException} */ (new Error('EPIPE')); e.code = 'EPIPE';
  s.pending.shift()?.done(e);
  out.line('three');
  assert.deepEqual(errors, ['EPIPE']);
  assert.equal(s.pending.length, 0, 'nothing more is written');
  assert.equal(await out.flush(5000), true);
});

test('flush waits for the queue, at most the time given', async () => {
  const s = heldStream();
  const out = new LineOutput(s.write);
  out.line('x');
  const t0 = Date.now();
  assert.equal(await out.flush(100), false, 'a stalled reader: not flushed');
  assert.ok(Date.now() - t0 < 1000);
  const flushed = out.flush(5000);
  s.drain();
  assert.equal(await flushed, true);
});
