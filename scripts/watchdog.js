#!/usr/bin/env node
// The watchdog of one stack. scripts/stack.js starts it detached (its own session and process group, so
// neither Ctrl-C nor a kill of the supervisor's group reaches it) before it starts any child, and tells it
// each child's process group on its stdin. When the supervisor dies in any way, SIGKILL included, the
// watchdog sees EOF on that pipe (and, as a backup, its parent pid change) and stops the whole stack:
// SIGTERM to every child group and to every process carrying the stack's marker (CELL_STACK_ID in
// /proc/<pid>/environ: roslaunch's nodes live in their own sessions, rosmaster/rosout outlive a killed
// roscore), SIGKILL to whatever is left after a short grace, until nothing is left; then it exits.
// After a clean shutdown the supervisor writes `done` and closes the pipe: the watchdog checks that
// nothing is left (sweeping as above if something is) and exits at once.
//
// Usage: node scripts/watchdog.js <stack-id> <supervisor-pid> [pgid...]
// stdin, one per line: `group <pgid>` (a child group started, restarts included), `forget <pgid>` (a dead
// child's group is empty: the supervisor restarted that child under a new group), `done` (clean shutdown finished).
import fs from 'node:fs';
import { fdOutput } from './supervise/output.js';

const GRACE_MS = 2000; // SIGTERM, then SIGKILL: everything is gone well within 5 s of the supervisor's death
const QUIET_MS = 250; // nothing left for this long (a child forked by the dying supervisor has exec'd by then)
const GIVE_UP_MS = 10_000;
const POLL_MS = 50;

const [stackId, supervisorArg, ...groupArgs] = process.argv.slice(2);
const supervisor = Number(supervisorArg);
if (!stackId || !Number.isInteger(supervisor) || supervisor <= 1) {
  console.error('usage: watchdog.js <stack-id> <supervisor-pid> [pgid...]');
  process.exit(2);
}
const MARKER = `CELL_STACK_ID=${stackId}`;
const validPid = (n) => Number.isInteger(n) && n > 1;
/** Process groups of the supervisor's children (each child leads its own group). */
const groups = new Set(groupArgs.map(Number).filter(validPid));

// Our stderr is the supervisor's: a closed, full or unread pipe must not stop us from cleaning up
// (process.stderr would block on a full pipe: supervise/output.js).
const err = fdOutput(2);
const log = (m) => err.line(`[watchdog] ${m}`);
/** @param {number} code */
const exit = async (code) => { await err.flush(200); process.exit(code); };

let clean = false;
let triggered = false;

let pending = '';
process.stdin.setEncoding('utf8');
process.stdin.on('data', (d) => {
  pending += d;
  for (let i; (i = pending.indexOf('\n')) >= 0; pending = pending.slice(i + 1)) {
    const [cmd, arg] = pending.slice(0, i).trim().split(/\s+/);
    if (cmd === 'group' && validPid(Number(arg))) groups.add(Number(arg));
    else if (cmd === 'forget') groups.delete(Number(arg));
    else if (cmd === 'done') clean = true;
  }
});
process.stdin.on('end', () => trigger('its pipe closed'));
process.stdin.on('close', () => trigger('its pipe closed'));
process.stdin.on('error', () => trigger('its pipe failed'));
// Backup for the pipe: our parent is the supervisor until it dies (then we are reparented).
const poll = setInterval(() => { if (process.ppid !== supervisor) trigger('it is gone'); }, 250);
if (process.ppid !== supervisor) trigger('it is gone');

/**
 * The processes to stop: every live process carrying the marker, and every member of a child group as long
 * as that group is still ours (its leader is gone, a zombie, or marked: a pgid cannot be reused while
 * members remain, and a reused one would have an unmarked live leader).
 * @returns {{pids: number[], groups: number[]}}
 */
function targets() {
  /** @type {Map<number, {pgrp: number, zombie: boolean, marked: boolean}>} */
  const procs = new Map();
  for (const d of fs.readdirSync('/proc')) {
    if (!/^\d+$/.test(d)) continue;
    const pid = Number(d);
    if (pid === process.pid) continue;
    let stat;
    try { stat = fs.readFileSync(`/proc/${d}/stat`, 'latin1'); } catch { continue; /* gone */ }
    const [state, , pgrp] = stat.slice(stat.lastIndexOf(')') + 2).split(' ');
    const zombie = state === 'Z' || state === 'X';
    let marked = false;
    try {
      marked = !zombie && fs.readFileSync(`/proc/${d}/environ`, 'latin1').split('\0').includes(MARKER);
    } catch { /* gone, or not readable: not ours */ }
    procs.set(pid, { pgrp: Number(pgrp), zombie, marked });
  }
  const ours = (g) => { const leader = procs.get(g); return !leader || leader.zombie || leader.marked; };
  const pids = [];
  const liveGroups = new Set();
  for (const [pid, p] of procs) {
    if (p.zombie || pid === supervisor) continue;
    const inGroup = groups.has(p.pgrp) && ours(p.pgrp);
    if (inGroup) liveGroups.add(p.pgrp);
    if (p.marked || inGroup) pids.push(pid);
  }
  return { pids, groups: [...liveGroups] };
}

const signal = (pid, sig) => { try { process.kill(pid, sig); } catch { /* gone */ } };
const describe = (pid) => {
  try { return `${pid} ${fs.readFileSync(`/proc/${pid}/cmdline`, 'latin1').replace(/\0/g, ' ').trim()}`; } catch { return `${pid}`; }
};

async function trigger(reason) {
  if (triggered) return;
  triggered = true;
  clearInterval(poll);
  if (clean && targets().pids.length === 0) return exit(0);
  log(clean ? 'processes of the stack survived its shutdown: stopping them'
    : `supervisor ${supervisor} died (${reason}): stopping its stack`);
  const t0 = Date.now();
  const termed = new Set();
  const termedGroups = new Set();
  let quietSince = 0;
  for (;;) {
    const now = Date.now();
    const left = targets();
    if (left.pids.length === 0) {
      quietSince ||= now;
      if (now - quietSince >= QUIET_MS) break;
    } else {
      quietSince = 0;
      const hard = now - t0 >= GRACE_MS;
      for (const g of left.groups) {
        if (!termedGroups.has(g)) { termedGroups.add(g); if (!hard) signal(-g, 'SIGTERM'); }
        if (hard) signal(-g, 'SIGKILL');
      }
      for (const pid of left.pids) {
        if (!termed.has(pid)) { termed.add(pid); if (!hard) signal(pid, 'SIGTERM'); }
        if (hard) signal(pid, 'SIGKILL');
      }
      if (now - t0 > GIVE_UP_MS) {
        log(`giving up; still running: ${left.pids.map(describe).join('; ')}`);
        return exit(1);
      }
    }
    await new Promise((r) => setTimeout(r, POLL_MS));
  }
  log(`stopped ${termed.size} processes in ${((Date.now() - t0 - QUIET_MS) / 1000).toFixed(1)} s`);
  return exit(0);
}
