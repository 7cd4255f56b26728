#!/usr/bin/env node
// Back-pressure in the BFF's /ros relay (docs/performance.md). The BFF (bff/src/server.js, its own process) relays
// a stand-in rosbridge (its own process: 30 Hz x 30 KB CBOR CompressedImage-like frames on /cell/bench/image,
// 100 Hz Float64MultiArray(6) JSON on /cell/bench, each message encoded once for all clients, as rosbridge does).
// Cases:
//   slow   a phone behind a 0.5 MB/s link: a network namespace of its own joined by a veth pair shaped with
//          `tc tbf` both ways; addresses only inside it and its peer; removed at the end. Root and ip/tc only,
//          skipped with a message otherwise. Age on arrival p95, first vs last third, BFF RSS growth.
//   stall  a client that stops reading (socket paused) for --stall-s seconds (300 by default): BFF RSS growth,
//          what arrives first after it resumes.
//   fast   25 clients at 100 Hz, alone and beside one stalled image client: p95 and loss.
//   rtt    a client 80 ms away (a loopback proxy delays every chunk 40 ms each way: this kernel has no netem), no
//          bandwidth cap: the frame rate the send window allows, and the age.
// Options: --cases slow,rtt,stall,fast  --slow-s 60  --rtt-s 30  --stall-s 300  --fast-s 20  --bff-dir <dir with src/server.js>
//   --frame-kb 30 (the image frames' size: e.g. what the video node sends a phone, bench/video_bench.mjs)
//   (--bff-dir lets the same cases run against another copy of bff/, e.g. the relay before the fix).
//   BENCH_QUICK=1 (npm run bench -- --quick): defaults --slow-s 10 --rtt-s 10 --stall-s 10 --fast-s 2, 2 s of reading before
//   the stall (5 s), the fast pair once (twice); options still win.
import { spawn, spawnSync } from 'node:child_process';
import fs from 'node:fs';
import http from 'node:http';
import net from 'node:net';
import https from 'node:https';
import os from 'node:os';
import path from 'node:path';
import { fileURLToPath } from 'node:url';
import { WebSocketServer, WebSocket } from 'ws';
import { encode as cborEncode, decode as cborDecode } from 'cbor-x';

const ROOT = path.resolve(path.dirname(fileURLToPath(import.meta.url)), '..');
const SELF = fileURLToPath(import.meta.url);
const args = process.argv.slice(2);
const opt = (name, dflt) => { const i = args.indexOf(`--${name}`); return i >= 0 ? args[i + 1] : dflt; };
const now = () => performance.timeOrigin + performance.now();
const sleep = (ms) => new Promise((r) => setTimeout(r, ms));
const QUICK = process.env.BENCH_QUICK === '1';
const pct = (xs, p) => { const s = [...xs].sort((a, b) => a - b); return s.length ? s[Math.min(s.length - 1, Math.floor((p / 100) * s.length))] : NaN; };
const rssMb = (pid) => { try { return Number(/VmRSS:\s+(\d+)/.exec(fs.readFileSync(`/proc/${pid}/status`, 'utf8'))[1]) / 1024; } catch { return NaN; } };
const IMAGE = '/cell/bench/image';
const ARRAY = '/cell/bench';
const FRAME_BYTES = Number(opt('frame-kb', 30)) * 1024;
const imageSub = { op: 'subscribe', id: 'img', topic: IMAGE, type: 'sensor_msgs/CompressedImage', queue_length: 1, compression: 'cbor' };
const stampMs = (m) => m.msg.header.stamp.secs * 1000 + m.msg.header.stamp.nsecs / 1e6;

// ---- role: stand-in rosbridge ----
if (opt('role') === 'upstream') {
  const wss = new WebSocketServer({ host: '127.0.0.1', port: Number(opt('port')) });
  /** @type {Map<string, Set<WebSocket>>} */
  const subs = new Map([[IMAGE, new Set()], [ARRAY, new Set()]]);
  wss.on('connection', (ws) => {
    ws.on('message', (d) => {
      let m; try { m = JSON.parse(d.toString()); } catch { return; }
      if (m.op === 'subscribe' && subs.has(m.topic)) subs.get(m.topic).add(ws);
      else if (m.op === 'call_service') ws.send(JSON.stringify({ op: 'service_response', service: m.service, id: m.id, values: {}, result: true }));
    });
    ws.on('close', () => { for (const s of subs.values()) s.delete(ws); });
  });
  const jpeg = Buffer.alloc(FRAME_BYTES, 7);
  let imgN = 0; let arrN = 0;
  const tick = (hz, fn) => { const t0 = now(); let k = 0; const step = () => { fn(); k++; setTimeout(step, Math.max(0, t0 + (k * 1000) / hz - now())); }; step(); };
  tick(30, () => {
    if (!subs.get(IMAGE).size) return;
    const t = now();
    const frame = cborEncode({ op: 'publish', topic: IMAGE, msg: { header: { seq: imgN++, stamp: { secs: Math.floor(t / 1000), nsecs: Math.round((t % 1000) * 1e6) }, frame_id: 'cam' }, format: 'jpeg', data: jpeg } });
    for (const ws of subs.get(IMAGE)) ws.send(frame, { binary: true });
  });
  tick(100, () => {
    if (!subs.get(ARRAY).size) return;
    const text = JSON.stringify({ op: 'publish', topic: ARRAY, msg: { layout: { dim: [], data_offset: 0 }, data: [now() / 1000, arrN++, 2, 3, 4, 5] } });
    for (const ws of subs.get(ARRAY)) ws.send(text);
  });
  process.on('SIGTERM', () => process.exit(0));
} else if (opt('role') === 'client') {
  // ---- role: the phone (run inside the namespace): subscribe to the image topic, print ages ----
  const ws = new WebSocket(opt('url'), { headers: { cookie: opt('cookie') }, rejectUnauthorized: false });
  const secs = Number(opt('secs'));
  ws.on('open', () => {
    ws.send(JSON.stringify({ op: 'subscribe', id: 'img', topic: IMAGE, type: 'sensor_msgs/CompressedImage', queue_length: 1, compression: 'cbor' }));
    const t0 = now();
    ws.on('message', (d) => {
      const m = cborDecode(d);
      if (m.op !== 'publish') return;
      const s = m.msg.header.stamp;
      process.stdout.write(`${(now() - t0).toFixed(1)} ${(now() - (s.secs * 1000 + s.nsecs / 1e6)).toFixed(1)}\n`);
    });
    setTimeout(() => { ws.close(); setTimeout(() => process.exit(0), 200); }, secs * 1000);
  });
  ws.on('error', (e) => { console.error(e.message); process.exit(1); });
} else {
  await main();
}

async function main() {
  const cases = opt('cases', 'slow,rtt,stall,fast').split(',');
  const bffDir = path.resolve(opt('bff-dir', path.join(ROOT, 'bff')));
  const base = Number(opt('port', 48080));
  const up = spawn(process.execPath, [SELF, '--role', 'upstream', '--port', String(base + 2), '--frame-kb', String(FRAME_BYTES / 1024)], { stdio: 'inherit' });
  /** @type {(() => void)[]} */
  const cleanups = [() => up.kill('SIGTERM')];
  const cleanup = () => { while (cleanups.length) { try { /** @type {() => void} */ (cleanups.pop())(); } catch { /* best effort */ } } };
  process.on('SIGINT', () => { cleanup(); process.exit(130); });
  console.log(`BFF back-pressure bench (${new Date().toISOString().slice(0, 10)}, ${os.cpus().length} cores, load ${os.loadavg()[0].toFixed(1)})${QUICK ? ', quick' : ''}, BFF from ${path.relative(ROOT, bffDir) || bffDir}`);
  try {
    await sleep(300);
    if (cases.includes('slow')) await slowCase(bffDir, base, cleanups);
    if (cases.includes('rtt')) await rttCase(bffDir, base);
    if (cases.includes('stall')) await stallCase(bffDir, base);
    if (cases.includes('fast')) await fastCase(bffDir, base);
  } finally {
    cleanup();
  }
}

/** Start bff/src/server.js with its own DATA_DIR; returns pid, cookie and a stop function. */
async function startBff(bffDir, base, host) {
  const dataDir = fs.mkdtempSync(path.join(os.tmpdir(), 'bff-bp-bench-'));
  const appDir = path.join(dataDir, 'app');
  fs.mkdirSync(appDir, { recursive: true });
  fs.writeFileSync(path.join(appDir, 'index.html'), '<!doctype html><title>bench</title>');
  const env = { ...process.env, DATA_DIR: dataDir, APP_DIR: appDir, PORT: String(base), TLS_PORT: String(base + 3), BFF_HOST: host,
    ROSBRIDGE_PORT: String(base + 2), ROS_MASTER_URI: `http://127.0.0.1:${base + 1}` };
  const r = spawnSync(process.execPath, [path.join(ROOT, 'bff/src/cli/users.js'), 'add', 'bench', '--role', 'admin', '--password-stdin'], { env, input: 'bench-password', encoding: 'utf8' });
  if (r.status !== 0) throw new Error(`users add: ${r.stderr}`);
  const proc = spawn(process.execPath, [path.join(bffDir, 'src/server.js')], { env, stdio: ['ignore', 'pipe', 'pipe'] });
  let out = '';
  proc.stdout.on('data', (d) => { out += d; });
  proc.stderr.on('data', (d) => { out += d; });
  const httpBase = host === '127.0.0.1' ? `http://${host}:${base}` : `https://${host}:${base + 3}`;
  const end = Date.now() + 20_000;
  while (!/listening on https/.test(out)) {
    if (proc.exitCode !== null || Date.now() > end) throw new Error(`BFF did not start:\n${out}`);
    await sleep(100);
  }
  await sleep(300);
  const cookie = await login(`${httpBase}/api/auth/login`);
  if (!cookie) throw new Error('login failed');
  const wsUrl = `${httpBase.replace('http', 'ws')}/ros`;
  return {
    pid: /** @type {number} */ (proc.pid), cookie, wsUrl, log: () => out,
    stop: async () => { const e = new Promise((r) => proc.once('exit', r)); proc.kill('SIGTERM'); await Promise.race([e, sleep(5000)]); fs.rmSync(dataDir, { recursive: true, force: true }); },
  };
}

/** POST the login over http or the BFF's self-signed https; returns the session cookie. */
function login(url) {
  const body = JSON.stringify({ username: 'bench', password: 'bench-password' });
  const mod = url.startsWith('https') ? https : http;
  return new Promise((resolve, reject) => {
    const req = mod.request(url, { method: 'POST', rejectUnauthorized: false, headers: { 'content-type': 'application/json', 'content-length': Buffer.byteLength(body) } }, (res) => {
      res.resume();
      resolve(String(res.headers['set-cookie']?.[0] || '').split(';')[0]);
    });
    req.on('error', reject);
    req.end(body);
  });
}

function openClient(url, cookie, sub, onMsg) {
  return new Promise((resolve, reject) => {
    const ws = new WebSocket(url, { headers: { cookie }, rejectUnauthorized: false });
    ws.on('open', () => { ws.send(JSON.stringify(sub)); resolve(ws); });
    ws.on('message', onMsg);
    ws.on('error', reject);
  });
}

function haveTools() {
  const has = (c) => (process.env.PATH || '').split(':').concat(['/usr/sbin', '/sbin']).some((d) => { try { fs.accessSync(path.join(d, c), fs.constants.X_OK); return true; } catch { return false; } });
  if (process.getuid?.() !== 0) return 'not root';
  if (!has('ip') || !has('tc')) return 'ip or tc missing, install iproute2';
  return '';
}

async function slowCase(bffDir, base, cleanups) {
  const secs = Number(opt('slow-s', QUICK ? 10 : 60));
  console.log(`\n== slow link: 0.5 MB/s veth in a namespace of its own, 30 Hz x ${FRAME_BYTES / 1024} KB frames, ${secs} s ==`);
  // 4 mbit/s = 0.5 MB/s each way; a 50 ms queue in the shaper, as a busy Wi-Fi access point might hold.
  await shapedCase(bffDir, base, cleanups, secs, ['tbf', 'rate', '4mbit', 'burst', '16kb', 'latency', '50ms']);
}

async function rttCase(bffDir, base) {
  const secs = Number(opt('rtt-s', QUICK ? 10 : 30));
  console.log(`\n== long link: 80 ms round trip (a proxy delays every chunk 40 ms each way), no bandwidth cap, 30 Hz x ${FRAME_BYTES / 1024} KB frames, ${secs} s ==`);
  const bff = await startBff(bffDir, base, '127.0.0.1');
  const proxyPort = base + 10;
  const proxy = delayProxy(proxyPort, base, 40);
  try {
    const url = bff.wsUrl.replace(`:${base}/`, `:${proxyPort}/`);
    const client = spawn(process.execPath, [SELF, '--role', 'client', '--url', url, '--cookie', bff.cookie, '--secs', String(secs)], { stdio: ['ignore', 'pipe', 'inherit'] });
    let text = '';
    client.stdout.on('data', (d) => { text += d; });
    await new Promise((r) => client.once('exit', r));
    const rows = text.trim().split('\n').filter(Boolean).map((l) => l.split(' ').map(Number)).filter((r) => r[0] >= 2000);
    const ages = rows.map((r) => r[1]);
    console.log(`after the first 2 s: ${(rows.length / (secs - 2)).toFixed(1)} frames/s, age p50 ${pct(ages, 50).toFixed(0)} ms, p95 ${pct(ages, 95).toFixed(0)} ms, max ${Math.max(...ages).toFixed(0)} ms`);
  } finally {
    proxy.close();
    await bff.stop();
  }
}

/**
 * A TCP proxy on loopback that holds every chunk `delayMs` in each direction, in order, with no bandwidth cap
 * (netem's delay, where the kernel has no netem). @param {number} port @param {number} target @param {number} delayMs
 */
function delayProxy(port, target, delayMs) {
  const server = net.createServer((c) => {
    const u = net.connect(target, '127.0.0.1');
    for (const [from, to] of [[c, u], [u, c]]) {
      from.setNoDelay(true);
      from.on('data', (d) => setTimeout(() => { if (!to.destroyed) to.write(d); }, delayMs));
      from.on('end', () => setTimeout(() => to.end(), delayMs));
      from.on('error', () => to.destroy());
      from.on('close', () => setTimeout(() => to.destroy(), delayMs + 10));
    }
  });
  server.listen(port, '127.0.0.1');
  return server;
}

/** One image client in a network namespace joined by a veth pair whose both ends have the qdisc `qdisc`. */
async function shapedCase(bffDir, base, cleanups, secs, qdisc) {
  const why = haveTools();
  if (why) { console.log(`skipped: ${why}`); return; }
  const id = `${process.pid % 100000}`;
  const ns = `bffbp${id}`; const v0 = `bpa${id}`; const v1 = `bpb${id}`;
  const run = (...argv) => { const r = spawnSync(argv[0], argv.slice(1), { encoding: 'utf8' }); if (r.status !== 0) throw new Error(`${argv.join(' ')}: ${r.stderr || r.error}`); };
  cleanups.push(() => spawnSync('ip', ['netns', 'del', ns]));
  run('ip', 'netns', 'add', ns);
  run('ip', 'link', 'add', v0, 'type', 'veth', 'peer', 'name', v1, 'netns', ns);
  run('ip', 'addr', 'add', '10.250.0.1/30', 'dev', v0);
  run('ip', 'link', 'set', v0, 'up');
  run('ip', '-n', ns, 'addr', 'add', '10.250.0.2/30', 'dev', v1);
  run('ip', '-n', ns, 'link', 'set', v1, 'up');
  run('ip', '-n', ns, 'link', 'set', 'lo', 'up');
  run('tc', 'qdisc', 'add', 'dev', v0, 'root', ...qdisc);
  run('ip', 'netns', 'exec', ns, 'tc', 'qdisc', 'add', 'dev', v1, 'root', ...qdisc);
  const bff = await startBff(bffDir, base, '10.250.0.1');
  try {
    const rss0 = rssMb(bff.pid);
    let rssMax = rss0;
    const rssAt = [];
    const probe = setInterval(() => { const r = rssMb(bff.pid); rssAt.push(r); rssMax = Math.max(rssMax, r); }, 1000);
    const client = spawn('ip', ['netns', 'exec', ns, process.execPath, SELF, '--role', 'client', '--url', bff.wsUrl, '--cookie', bff.cookie, '--secs', String(secs)], { stdio: ['ignore', 'pipe', 'inherit'] });
    let text = '';
    client.stdout.on('data', (d) => { text += d; });
    await new Promise((r) => client.once('exit', r));
    clearInterval(probe);
    const rows = text.trim().split('\n').filter(Boolean).map((l) => l.split(' ').map(Number));
    const ages = rows.map((r) => r[1]);
    const third = (k) => rows.filter((r) => r[0] >= (k * secs * 1000) / 3 && r[0] < ((k + 1) * secs * 1000) / 3).map((r) => r[1]);
    const [a, , c] = [third(0), third(1), third(2)];
    console.log(`frames received ${rows.length} (${(rows.length / secs).toFixed(1)}/s), age p50 ${pct(ages, 50).toFixed(0)} ms, p95 ${pct(ages, 95).toFixed(0)} ms, max ${Math.max(...ages).toFixed(0)} ms`);
    console.log(`p95 first third ${pct(a, 95).toFixed(0)} ms, last third ${pct(c, 95).toFixed(0)} ms (ratio ${(pct(c, 95) / pct(a, 95)).toFixed(2)})`);
    const r1 = rssAt[Math.floor(rssAt.length / 3)] ?? NaN;
    console.log(`BFF RSS ${rss0.toFixed(1)} MB at start, ${r1.toFixed(1)} MB after a third, ${rssAt[rssAt.length - 1]?.toFixed(1)} MB at the end, max ${rssMax.toFixed(1)} MB`);
  } finally {
    await bff.stop();
    spawnSync('ip', ['netns', 'del', ns]);
  }
}

async function stallCase(bffDir, base) {
  const secs = Number(opt('stall-s', QUICK ? 10 : 300));
  console.log(`\n== stalled reader: 30 Hz x 30 KB frames, client stops reading for ${secs} s (loopback) ==`);
  const bff = await startBff(bffDir, base, '127.0.0.1');
  try {
    /** @type {{at: number, stamp: number}[]} */
    const got = [];
    const ws = await openClient(bff.wsUrl, bff.cookie, imageSub, (d) => { const m = cborDecode(d); if (m.op === 'publish') got.push({ at: now(), stamp: stampMs(m) }); });
    await sleep(QUICK ? 2000 : 5000);
    const rss0 = rssMb(bff.pid);
    let rssMax = rss0;
    /** @type {any} */ (ws)._socket.pause();
    const pausedAt = now();
    const end = Date.now() + secs * 1000;
    while (Date.now() < end) { await sleep(1000); rssMax = Math.max(rssMax, rssMb(bff.pid)); }
    const rssEnd = rssMb(bff.pid);
    const before = got.length;
    const resumedAt = now();
    /** @type {any} */ (ws)._socket.resume();
    await sleep(2000);
    const after = got.slice(before);
    const stale = after.filter((x) => x.stamp < pausedAt + 50);
    const fresh = after.find((x) => x.stamp >= pausedAt + 50);
    console.log(`BFF RSS ${rss0.toFixed(1)} MB when the reader stopped, max ${rssMax.toFixed(1)} MB during the stall (+${(rssMax - rss0).toFixed(1)} MB), ${rssEnd.toFixed(1)} MB at its end`);
    console.log(`after resume: ${stale.length} frames written before the stall arrive first (within ${stale.length ? (stale[stale.length - 1].at - resumedAt).toFixed(0) : 0} ms), then the first frame queued in the stall: ` +
      (fresh ? `age on arrival ${(fresh.at - fresh.stamp).toFixed(0)} ms, ${(fresh.at - resumedAt).toFixed(0)} ms after resume` : 'none within 2 s'));
    ws.close();
  } finally {
    await bff.stop();
  }
}

async function fastCase(bffDir, base) {
  const secs = Number(opt('fast-s', QUICK ? 2 : 20));
  console.log(`\n== 25 clients x 100 Hz Float64MultiArray(6) JSON, ${secs} s, alone and beside one stalled image client (loopback) ==`);
  console.log('run | msgs/s/client | lost | p50 ms | p95 ms | BFF RSS MB');
  const bff = await startBff(bffDir, base, '127.0.0.1');
  try {
    for (const withSlow of QUICK ? [false, true] : [false, true, false, true]) {
      let slow;
      if (withSlow) {
        slow = await openClient(bff.wsUrl, bff.cookie, imageSub, () => {});
        await sleep(500);
        /** @type {any} */ (slow)._socket.pause();
      }
      const lat = []; let received = 0; let lost = 0; let measuring = false;
      const clients = await Promise.all(Array.from({ length: 25 }, () => {
        let last = -1;
        return openClient(bff.wsUrl, bff.cookie, { op: 'subscribe', id: 'b', topic: ARRAY, type: 'std_msgs/Float64MultiArray' }, (d) => {
          const m = JSON.parse(d.toString());
          if (m.op !== 'publish') return;
          const n = m.msg.data[1];
          if (measuring) { received++; lat.push(now() - m.msg.data[0] * 1000); if (last >= 0 && n !== last + 1) lost += n - last - 1; }
          last = n;
        });
      }));
      await sleep(1000);
      measuring = true;
      await sleep(secs * 1000);
      measuring = false;
      const rss = rssMb(bff.pid);
      for (const ws of clients) ws.close();
      if (slow) { /** @type {any} */ (slow)._socket.resume(); slow.close(); }
      console.log(`${withSlow ? 'beside a stalled client' : 'alone                  '} | ${(received / 25 / secs).toFixed(1).padStart(13)} | ${String(lost).padStart(4)} | ${pct(lat, 50).toFixed(2).padStart(6)} | ${pct(lat, 95).toFixed(2).padStart(6)} | ${rss.toFixed(0).padStart(10)}`);
      await sleep(1000);
    }
  } finally {
    await bff.stop();
  }
}
