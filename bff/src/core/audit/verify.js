// Verifies the audit log's hash chain (chain.js) over the contents of its files: a pure function, plus a small
// reader of a data dir for the CLI (`npm run audit -- verify`, bff/src/cli/audit.js).
//
// What it reports, in the order of the log (the first problem only; a torn line does not hide a later one):
// - altered:  an entry's hash does not match its content, or an entry was rewritten with a recomputed hash (the
//             next entry chains to a different one), or it is not a valid entry;
// - removed:  seq jumps (entries gone from the middle, or a whole rotated file), or the tail is shorter than the
//             head file says;
// - inserted: an entry that is not part of the chain (the entries around it chain to each other), or entries past
//             the head;
// - torn:     a line that is not a complete entry while the chain runs on around it (a crash mid-write);
// - head:     the head file is missing or damaged while the log has chained entries.
// Repairs the BFF made at start after a crash or power loss (audit-log.js: a torn last line cut off, a head moved on)
// are chained entries themselves; a log that is otherwise intact passes, and the summary lists them.
// The oldest retained chained entry is the anchor: its `prev` is taken on trust, since rotation drops the oldest
// file. Entries from before the chain (no seq/prev/hash) at the start are a legacy prefix, reported, not an error.
import fs from 'node:fs';
import path from 'node:path';
import {
  GENESIS, HEAD_BEHIND_OP, HEAD_FILE, LOG_FILE, TORN_WRITE_OP, entryHash, isChained, isLegacy, parseHead,
} from './chain.js';

/**
 * @typedef {{name: string, text: string}} AuditFile  one log file, by its name in the data dir
 * @typedef {'altered'|'removed'|'inserted'|'torn'|'head'} ProblemKind
 * @typedef {{kind: ProblemKind, file: string|null, line: number|null, seq: number|null, message: string,
 *   text: string}} AuditProblem  text: the line to print ("audit.log.1 line 17 (seq 233): altered: ...")
 * @typedef {{ok: boolean, entries: number, legacy: number, firstSeq: number|null, lastSeq: number|null,
 *   files: string[], anchor: {file: string, line: number, seq: number, genesis: boolean}|null,
 *   problem: AuditProblem|null, torn: AuditProblem[], repairs: AuditRepair[], summary: string}} AuditVerdict
 * @typedef {{kind: 'torn_write'|'head_behind', file: string, line: number, seq: number, detail: string}} AuditRepair
 *   an entry the BFF wrote at start to record a repair (in the verified part of the chain)
 * @typedef {{file: string, line: number, raw: string, terminated: boolean,
 *   type: 'chained'|'legacy'|'bad', entry: any, hashOk: boolean}} Item
 */

/**
 * @param {{files: AuditFile[], head: string|null}} input  files oldest first (audit.log.N ... audit.log.1,
 *   audit.log); head: the text of the head file, null when there is none
 * @returns {AuditVerdict}
 */
export function verifyAuditLog({ files, head }) {
  /** @type {Item[]} */
  const items = [];
  for (const f of files) {
    const lines = f.text.split('\n');
    const terminatedAll = f.text.endsWith('\n');
    lines.forEach((raw, i) => {
      if (raw === '') return;
      const terminated = i < lines.length - 1 || terminatedAll;
      let entry;
      let json = true;
      try { entry = JSON.parse(raw); } catch { json = false; }
      const type = json && isChained(entry) ? 'chained' : json && isLegacy(entry) ? 'legacy' : 'bad';
      items.push({ file: f.name, line: i + 1, raw, terminated, type, entry: json ? entry : undefined, hashOk: type === 'chained' && entryHash(entry) === entry.hash });
    });
  }

  /** @type {Item[]} the chain as verified so far */
  const chain = [];
  /** @type {Map<string, number>} hash -> index in chain */
  const byHash = new Map();
  let legacy = 0;
  /** @type {AuditProblem[]} */
  const torn = [];
  /** @type {AuditProblem|null} */
  let problem = null;
  const last = () => chain[chain.length - 1];
  /** @param {Item} a @param {Item} b */
  const follows = (a, b) => b.entry.prev === a.entry.hash && b.entry.seq === a.entry.seq + 1;
  /** @param {number} i */
  const nextChained = (i) => items.slice(i + 1).find((x) => x.type === 'chained');

  for (let i = 0; i < items.length && !problem; i++) {
    const it = items[i];
    const prev = last();
    if (it.type === 'legacy') {
      if (!prev) { legacy++; continue; }
      const next = nextChained(i);
      problem = next && follows(prev, next)
        ? at('inserted', it, 'an entry without seq/hash inside the chain')
        : at('altered', it, `an entry without seq/hash in place of seq ${prev.entry.seq + 1}`);
      break;
    }
    if (it.type === 'bad') {
      const next = nextChained(i);
      const parsed = it.entry !== undefined;
      if (!parsed && !it.terminated && i === items.length - 1) torn.push(at('torn', it, 'incomplete last line (a crash mid-write?)'));
      else if (!parsed && (!prev || !next || follows(prev, next))) torn.push(at('torn', it, 'not a complete entry (an interrupted write; the chain runs on around it)'));
      else problem = at('altered', it, parsed ? 'not a valid entry (malformed seq/prev/hash)' : 'not a valid JSON entry');
      continue;
    }
    if (!it.hashOk) { problem = at('altered', it, 'hash does not match its content'); break; }
    if (!prev || follows(prev, it)) { byHash.set(it.entry.hash, chain.length); chain.push(it); continue; }

    // The link between prev and it is broken: find which entry is the odd one out.
    const next = nextChained(i);
    const back = byHash.get(it.entry.prev);
    if (next && follows(prev, next)) {
      problem = at('inserted', it, `not part of the chain (the next entry, seq ${next.entry.seq} at ${where(next)}, chains to seq ${prev.entry.seq})`);
    } else if (back !== undefined && back < chain.length - 1 && it.entry.seq === chain[back].entry.seq + 1) {
      const first = chain[back + 1];
      problem = at('inserted', first, `not part of the chain (seq ${it.entry.seq} at ${where(it)} chains to seq ${chain[back].entry.seq}, before it)`);
    } else if (it.entry.seq > prev.entry.seq + 1) {
      const gap = it.entry.seq - prev.entry.seq - 1;
      problem = at('removed', it, `seq jumps from ${prev.entry.seq} to ${it.entry.seq} (${gap} ${gap === 1 ? 'entry' : 'entries'} missing${prev.file !== it.file ? `, between ${prev.file} and ${it.file}` : ''})`);
    } else if (it.entry.seq === prev.entry.seq + 1) {
      problem = at('altered', prev, `rewritten with a recomputed hash (the next entry, seq ${it.entry.seq} at ${where(it)}, chains to a different hash)`);
    } else if (it.entry.prev === prev.entry.hash) {
      problem = at('altered', it, `seq ${it.entry.seq} does not follow seq ${prev.entry.seq} (rewritten with a recomputed hash)`);
    } else {
      problem = at('inserted', it, `seq goes back from ${prev.entry.seq} to ${it.entry.seq}`);
    }
  }

  const names = files.map((f) => f.name);
  const end = last();
  if (!problem) problem = checkHead(head, chain);

  const anchor = chain[0] ? { file: chain[0].file, line: chain[0].line, seq: chain[0].entry.seq, genesis: chain[0].entry.prev === GENESIS } : null;
  const tornNote = torn.length ? `; ${torn.length} torn ${torn.length === 1 ? 'line' : 'lines'}` : '';
  /** @type {AuditRepair[]} */
  const repairs = chain.filter((x) => x.entry.op === TORN_WRITE_OP || x.entry.op === HEAD_BEHIND_OP).map((x) => ({
    kind: x.entry.op === TORN_WRITE_OP ? 'torn_write' : 'head_behind', file: x.file, line: x.line, seq: x.entry.seq, detail: String(x.entry.detail ?? ''),
  }));
  let extent;
  if (!anchor) extent = `${legacy} legacy unchained ${legacy === 1 ? 'entry' : 'entries'}, no chained entries`;
  else {
    extent = `${chain.length} ${chain.length === 1 ? 'entry' : 'entries'}, seq ${anchor.seq}..${end.entry.seq}, files ${names.join(', ')}; `
      + `chain starts at seq ${anchor.seq} in ${anchor.file}${anchor.line > 1 ? ` line ${anchor.line}` : ''}`
      + (anchor.genesis ? ' (its beginning)' : ' (older entries rotated away; its prev hash is taken as the anchor)')
      + (legacy ? `; ${legacy} legacy unchained ${legacy === 1 ? 'entry' : 'entries'} before it` : '')
      + repairNote(repairs, 'torn_write', 'torn write', 'torn writes') + repairNote(repairs, 'head_behind', 'head left behind', 'heads left behind');
  }
  if (!files.length && !head) extent = '0 entries (no audit log)';
  const ok = !problem && !torn.length;
  const summary = ok ? `audit log intact: ${extent}`
    : problem ? `audit log NOT intact: ${problem.text}`
      : `audit log damaged: ${torn[0].text}; otherwise intact: ${extent}${tornNote}`;
  return {
    ok, entries: chain.length, legacy, firstSeq: anchor?.seq ?? null, lastSeq: end?.entry.seq ?? null, files: names, anchor,
    problem: problem || torn[0] || null, torn, repairs, summary,
  };
}

/**
 * After an intact walk: the head file must agree with where the chain ends.
 * @param {string|null} headText @param {Item[]} chain @returns {AuditProblem|null}
 */
function checkHead(headText, chain) {
  const end = chain[chain.length - 1];
  const head = headText === null ? null : parseHead(headText);
  if (headText !== null && !head) return problemOf('head', null, `${HEAD_FILE} is damaged: a removed tail cannot be ruled out`);
  if (!end) return head ? problemOf('removed', null, `tail removed: the head says seq ${head.seq}, the log has no chained entries`) : null;
  if (!head) return problemOf('head', null, `${HEAD_FILE} is missing: a removed tail cannot be ruled out (the log ends at seq ${end.entry.seq})`);
  if (head.seq > end.entry.seq) {
    return problemOf('removed', null, `tail removed: the head says seq ${head.seq}, the log ends at ${end.entry.seq} (${where(end)})`);
  }
  const k = chain.findIndex((x) => x.entry.seq === head.seq);
  if (k < 0) return problemOf('head', null, `${HEAD_FILE} (seq ${head.seq}) is older than the whole log (seq ${chain[0].entry.seq}..${end.entry.seq})`);
  if (chain[k].entry.hash !== head.hash) return at('altered', chain[k], 'does not match the head: the entry (and any after it) was rewritten');
  if (k < chain.length - 1) {
    return at('inserted', chain[k + 1], `after the head (seq ${head.seq}): forged at the end, or the BFF stopped between writing this entry and the head`);
  }
  return null;
}

/**
 * "; 2 torn writes repaired at start (seq 57 in audit.log.1 line 3: cut ...; seq 90 ...)", the first few listed.
 * @param {AuditRepair[]} repairs @param {AuditRepair['kind']} kind @param {string} one @param {string} many
 */
function repairNote(repairs, kind, one, many) {
  const r = repairs.filter((x) => x.kind === kind);
  if (!r.length) return '';
  const shown = r.slice(0, 5).map((x) => `seq ${x.seq} in ${x.file} line ${x.line}: ${x.detail}`);
  return `; ${r.length} ${r.length === 1 ? one : many} repaired at start (${shown.join('; ')}${r.length > shown.length ? '; ...' : ''})`;
}

/** @param {Item} it */
function where(it) {
  return `${it.file} line ${it.line}`;
}

/** @param {ProblemKind} kind @param {Item} it @param {string} message @returns {AuditProblem} */
function at(kind, it, message) {
  const seq = it.type === 'chained' ? it.entry.seq : null;
  return { kind, file: it.file, line: it.line, seq, message, text: `${where(it)}${seq !== null ? ` (seq ${seq})` : ''}: ${kind}: ${message}` };
}

/** @param {ProblemKind} kind @param {string|null} file @param {string} message @returns {AuditProblem} */
function problemOf(kind, file, message) {
  return { kind, file, line: null, seq: null, message, text: message.startsWith('tail removed') ? message : `${kind}: ${message}` };
}

/**
 * Reads the audit files of a data dir: audit.log.N (highest, oldest, first) ... audit.log.1, audit.log, and the
 * head. A BFF may be writing meanwhile: the head is read before and after the files, and all is read again (a few
 * times at most) when it moved, so the files and the head belong together. Throws when the dir cannot be read.
 * @param {string} dir @returns {{files: AuditFile[], head: string|null}}
 */
export function readAuditDir(dir) {
  const readHead = () => {
    try { return fs.readFileSync(path.join(dir, HEAD_FILE), 'utf8'); } catch (e) { if (e.code === 'ENOENT') return null; throw e; }
  };
  const rotated = new RegExp(`^${LOG_FILE.replace('.', '\\.')}(?:\\.(\\d+))?$`);
  let snapshot;
  for (let attempt = 0; attempt < 5; attempt++) {
    const before = readHead();
    const names = fs.readdirSync(dir)
      .map((name) => ({ name, m: rotated.exec(name) }))
      .filter((x) => x.m)
      .sort((a, b) => Number(b.m[1] ?? 0) - Number(a.m[1] ?? 0))
      .map((x) => x.name);
    const files = [];
    for (const name of names) {
      try { files.push({ name, text: fs.readFileSync(path.join(dir, name), 'utf8') }); } catch (e) { if (e.code !== 'ENOENT') throw e; }
    }
    const head = readHead();
    snapshot = { files, head };
    if (head === before && files.length === names.length) break;
  }
  return snapshot;
}
