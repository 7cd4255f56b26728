// An arm's URDF for the browser: read from a file or from a ROS parameter (the master's XML-RPC getParam), checked
// to be a <robot> document, its mesh filenames rewritten to the mesh route; and the mesh files those names stood for
// (file://, absolute, relative, package:// through ROS_PACKAGE_PATH). Everything a client can cause here is a
// SceneError with a 4xx status and a message that names no server path.
import fs from 'node:fs';
import http from 'node:http';
import path from 'node:path';
import { createHash } from 'node:crypto';
import { fileURLToPath } from 'node:url';
import { DOMParser, XMLSerializer, onErrorStopParsing } from '@xmldom/xmldom';

/** A client error: its status, a message that names no server path, and the same as a stable code and params for the app. */
export class SceneError extends Error {
  /** @param {number} status @param {string} message @param {string} [code] @param {Record<string, string | number>} [params] */
  constructor(status, message, code = undefined, params = undefined) {
    super(message);
    this.status = status;
    this.code = code;
    this.params = params;
  }
}

/** The largest URDF accepted, from a file or from the master (a URDF with inline meshes is still far below). */
export const MAX_URDF_BYTES = 16 * 1024 * 1024;
/** How long the master may take to answer getParam. */
export const MASTER_TIMEOUT_MS = 3000;
/** The caller id the BFF gives the master (as the health check's getPid). */
const CALLER_ID = '/cell_bff';

const xmlEscape = (/** @type {string} */ s) => s.replace(/&/g, '&amp;').replace(/</g, '&lt;').replace(/>/g, '&gt;').replace(/"/g, '&quot;');
/** A parser's first line, short: what was wrong, not the whole document. @param {unknown} e */
const parseProblem = (e) => String(/** @type {any} */ (e)?.message || e).split('\n')[0].slice(0, 200);
/** A parser that stops at the first error (xmldom's default only reports it). */
const parser = () => new DOMParser({ onError: onErrorStopParsing });

/** @param {any} node @returns {any[]} its element children */
const elements = (node) => Array.from(node?.childNodes || []).filter((n) => /** @type {any} */ (n).nodeType === 1);

// ----------------------------------------------------------------------------------------------- XML-RPC

/**
 * One XML-RPC <value> as a JS value (strings, numbers, booleans, arrays, structs; base64 and dates as their text).
 * @param {any} value
 * @returns {unknown}
 */
export function decodeValue(value) {
  const [typed] = elements(value);
  if (!typed) return value.textContent ?? ''; // a bare <value>text</value> is a string
  const text = typed.textContent ?? '';
  switch (typed.nodeName) {
    case 'string': return text;
    case 'int': case 'i4': case 'i8': return Number.parseInt(text.trim(), 10);
    case 'double': return Number(text.trim());
    case 'boolean': return text.trim() === '1';
    case 'nil': return null;
    case 'array': {
      const data = elements(typed).find((n) => n.nodeName === 'data');
      return elements(data).filter((n) => n.nodeName === 'value').map(decodeValue);
    }
    case 'struct':
      return Object.fromEntries(elements(typed).filter((n) => n.nodeName === 'member').map((m) => {
        const parts = elements(m);
        const name = parts.find((n) => n.nodeName === 'name')?.textContent ?? '';
        const v = parts.find((n) => n.nodeName === 'value');
        return [name, v ? decodeValue(v) : null];
      }));
    default: return { [typed.nodeName]: text };
  }
}

/**
 * An XML-RPC methodResponse: {value} its one parameter, or {fault} the fault's string.
 * @param {string} text
 * @returns {{value: unknown} | {fault: string}}
 */
export function parseMethodResponse(text) {
  const doc = parser().parseFromString(text, 'text/xml'); // throws on malformed XML
  const root = doc.documentElement;
  if (root?.nodeName !== 'methodResponse') throw new Error(`not an XML-RPC methodResponse (<${root?.nodeName}>)`);
  const [body] = elements(root);
  if (body?.nodeName === 'fault') {
    const fault = decodeValue(elements(body).find((n) => n.nodeName === 'value'));
    return { fault: String(/** @type {any} */ (fault)?.faultString ?? JSON.stringify(fault)) };
  }
  const value = elements(elements(body).find((n) => n.nodeName === 'param')).find((n) => n.nodeName === 'value');
  if (body?.nodeName !== 'params' || !value) throw new Error('an XML-RPC methodResponse without a parameter');
  return { value: decodeValue(value) };
}

/**
 * POST one XML-RPC call to the master. Resolves with the response body; rejects with a SceneError 409 when the
 * master does not answer (refused, timed out, not http) or answers with something that is not XML-RPC over HTTP 200.
 * @param {string} masterUri @param {string} body @param {{timeoutMs?: number}} [o]
 * @returns {Promise<string>}
 */
function postXmlRpc(masterUri, body, { timeoutMs = MASTER_TIMEOUT_MS } = {}) {
  /** @param {string} why @param {string} code @param {Record<string, string>} [more] */
  const fails = (why, code, more = {}) => new SceneError(409, `the ROS master at ${masterUri} does not answer${why}: the URDF parameter cannot be read`, code, { master: masterUri, ...more });
  const down = () => fails('', 'scene.master_down');
  const badUri = (/** @type {string} */ why) => fails(why, 'scene.master_bad_uri');
  return new Promise((resolve, reject) => {
    let url;
    try {
      url = new URL(masterUri);
    } catch {
      reject(badUri(' (not a URI)'));
      return;
    }
    if (url.protocol !== 'http:') {
      reject(badUri(' (not an http:// URI)'));
      return;
    }
    const req = http.request({
      host: url.hostname.replace(/^\[|\]$/g, ''), port: url.port || 11311, path: url.pathname || '/', method: 'POST', timeout: timeoutMs,
      headers: { 'content-type': 'text/xml', 'content-length': Buffer.byteLength(body) },
    }, (res) => {
      /** @type {Buffer[]} */
      const chunks = [];
      let size = 0;
      res.on('data', (c) => {
        size += c.length;
        if (size > MAX_URDF_BYTES) {
          req.destroy();
          reject(new SceneError(422, `the ROS master's answer is larger than ${MAX_URDF_BYTES} bytes: not a URDF this view can load`, 'scene.master_answer_too_large', { limit: MAX_URDF_BYTES }));
        } else chunks.push(c);
      });
      res.on('end', () => {
        if (res.statusCode !== 200) reject(fails(` with XML-RPC (HTTP ${res.statusCode})`, 'scene.master_not_xmlrpc', { detail: `HTTP ${res.statusCode}` }));
        else resolve(Buffer.concat(chunks).toString('utf8'));
      });
      res.on('error', () => reject(down()));
    });
    // A stalled answer is a master that does not answer, too.
    const timer = setTimeout(() => { req.destroy(); reject(down()); }, timeoutMs);
    req.on('close', () => clearTimeout(timer));
    req.on('timeout', () => { req.destroy(); reject(down()); });
    req.on('error', () => reject(down()));
    req.end(body);
  });
}

/**
 * A ROS parameter's value, read from the master (getParam(caller_id, key) -> [code, statusMessage, value]).
 * Rejects with SceneError: 409 the master does not answer, 404 the parameter is not set.
 * @param {string} masterUri @param {string} key @param {{timeoutMs?: number}} [o]
 * @returns {Promise<unknown>}
 */
export async function getParam(masterUri, key, o = {}) {
  const call = '<?xml version="1.0"?><methodCall><methodName>getParam</methodName><params>'
    + `<param><value><string>${xmlEscape(CALLER_ID)}</string></value></param>`
    + `<param><value><string>${xmlEscape(key)}</string></value></param></params></methodCall>`;
  const text = await postXmlRpc(masterUri, call, o);
  let answer;
  try {
    answer = parseMethodResponse(text);
  } catch (e) {
    const detail = parseProblem(e);
    throw new SceneError(409, `the ROS master at ${masterUri} does not answer with XML-RPC (${detail}): the URDF parameter cannot be read`,
      'scene.master_not_xmlrpc', { master: masterUri, detail });
  }
  if ('fault' in answer) {
    const detail = answer.fault.slice(0, 200);
    throw new SceneError(409, `the ROS master at ${masterUri} refused getParam ${key}: ${detail}`, 'scene.master_refused', { master: masterUri, param: key, detail });
  }
  const v = answer.value;
  if (!Array.isArray(v) || v.length < 3 || typeof v[0] !== 'number') {
    throw new SceneError(409, `the ROS master at ${masterUri} answered getParam with no [code, statusMessage, value]: the URDF parameter cannot be read`,
      'scene.master_bad_answer', { master: masterUri });
  }
  if (v[0] !== 1) throw new SceneError(404, `no URDF on the parameter ${key} (is the arm's driver up?)`, 'scene.param_unset', { param: key });
  return v[2];
}

// ----------------------------------------------------------------------------------------------- URDF

/** @typedef {{filename: string, name: string}} MeshRef a mesh filename as the URDF gives it, and its base name */

/** The URL a URDF's mesh number i gets. @param {string} group @param {number} i @param {string} name */
export const meshUrl = (group, i, name) => `/api/scene/arms/${encodeURIComponent(group)}/meshes/${i}/${encodeURIComponent(name)}`;

/**
 * The base name of a mesh filename (a path, file:// or package:// URI), as the browser sees it.
 * @param {string} filename
 */
export function meshName(filename) {
  let p = filename.trim();
  if (/^file:/i.test(p)) {
    try {
      p = fileURLToPath(p);
    } catch { /* keep the text */ }
  } else if (/^[a-z][a-z0-9+.-]*:\/\//i.test(p)) {
    p = p.replace(/[?#].*$/, '');
  }
  return p.split(/[\\/]/).filter(Boolean).pop() || 'mesh';
}

/**
 * Check that text is a URDF (a well-formed XML document whose root is <robot>) and rewrite every
 * <mesh filename="..."> to the mesh route: mesh i of the distinct filenames, in document order.
 * @param {string} text @param {string} group @param {string} what names the source in messages ("the parameter /x")
 * @param {{param: string} | {file: string}} [source] the same for the errors' codes: a parameter's name or a file's
 *   (scene.param_not_urdf {param, detail}, scene.file_root_not_robot {file, root}, ...)
 * @returns {{text: string, meshes: MeshRef[]}}
 */
export function prepareUrdf(text, group, what, source = undefined) {
  /** A 422 naming the source. @param {string} problem @param {[string, string]} codes for a parameter, for a file @param {Record<string, string>} more */
  const notUrdf = (problem, [paramCode, fileCode], more) => new SceneError(422, `${what} does not hold a URDF: ${problem}`,
    source && ('param' in source ? paramCode : fileCode), source && { ...source, ...more });
  let doc;
  try {
    doc = parser().parseFromString(text, 'text/xml');
  } catch (e) {
    const detail = parseProblem(e);
    throw notUrdf(detail, ['scene.param_not_urdf', 'scene.file_not_urdf'], { detail });
  }
  const root = doc.documentElement;
  if (root?.nodeName !== 'robot') {
    const name = String(root?.nodeName);
    throw notUrdf(`its root element is <${name}>, not <robot>`, ['scene.param_root_not_robot', 'scene.file_root_not_robot'], { root: name });
  }
  /** @type {MeshRef[]} */
  const meshes = [];
  /** @type {Map<string, number>} */
  const index = new Map();
  for (const el of Array.from(doc.getElementsByTagName('mesh'))) {
    const filename = el.getAttribute('filename');
    if (!filename) continue;
    if (!index.has(filename)) {
      index.set(filename, meshes.length);
      meshes.push({ filename, name: meshName(filename) });
    }
    const i = index.get(filename);
    el.setAttribute('filename', meshUrl(group, i, meshes[i].name));
  }
  return { text: new XMLSerializer().serializeToString(doc), meshes };
}

/** A strong ETag of a text. @param {string} text */
export const etagOf = (text) => `"${createHash('sha256').update(text).digest('base64url').slice(0, 32)}"`;

// ----------------------------------------------------------------------------------------------- meshes

/** @type {Record<string, string>} the mesh formats served, with their Content-Type */
const MESH_TYPES = { '.stl': 'model/stl', '.dae': 'model/vnd.collada+xml', '.obj': 'model/obj' };

/** Whether a file name is of a mesh format the view draws. @param {string} name */
export const isMeshFile = (name) => path.extname(name).toLowerCase() in MESH_TYPES;

/** The Content-Type a mesh is served with, by its extension. @param {string} name */
export function meshType(name) {
  return MESH_TYPES[path.extname(name).toLowerCase()] || 'application/octet-stream';
}

/** @param {string} p */
const isFile = (p) => { try { return fs.statSync(p).isFile(); } catch { return false; } };
/** @param {string} p */
const isDir = (p) => { try { return fs.statSync(p).isDirectory(); } catch { return false; } };

/** How deep under a ROS_PACKAGE_PATH entry packages are looked for (a workspace's src/<repo>/<group>/<pkg>). */
const CRAWL_DEPTH = 5;

/**
 * The directory of ROS package pkg: for each ROS_PACKAGE_PATH entry (in order) the entry itself when it is named pkg
 * and has a package.xml, else a directory named pkg with a package.xml found under it (packages do not nest; hidden
 * directories and those with CATKIN_IGNORE are skipped); failing that, <entry>/pkg without a package.xml.
 * @param {string} pkg @param {string} rosPackagePath colon-separated
 * @returns {string | null}
 */
export function findPackage(pkg, rosPackagePath) {
  const entries = rosPackagePath.split(path.delimiter).filter(Boolean).map((e) => path.resolve(e));
  /** @param {string} dir @param {number} depth @returns {string | null} */
  const crawl = (dir, depth) => {
    if (depth > CRAWL_DEPTH) return null;
    let list;
    try {
      list = fs.readdirSync(dir, { withFileTypes: true });
    } catch {
      return null;
    }
    if (list.some((e) => e.name === 'CATKIN_IGNORE')) return null;
    for (const e of list) {
      if (e.name.startsWith('.') || !(e.isDirectory() || (e.isSymbolicLink() && isDir(path.join(dir, e.name))))) continue;
      const sub = path.join(dir, e.name);
      if (isFile(path.join(sub, 'package.xml'))) {
        if (e.name === pkg) return sub;
        continue;
      }
      const found = crawl(sub, depth + 1);
      if (found) return found;
    }
    return null;
  };
  for (const entry of entries) {
    if (path.basename(entry) === pkg && isFile(path.join(entry, 'package.xml'))) return entry;
    if (isFile(path.join(entry, pkg, 'package.xml'))) return path.join(entry, pkg);
    if (isFile(path.join(entry, 'package.xml'))) continue; // a package itself: nothing under it
    const found = crawl(entry, 0);
    if (found) return found;
  }
  for (const entry of entries) if (isDir(path.join(entry, pkg))) return path.join(entry, pkg);
  return null;
}

/**
 * The absolute path of a mesh filename, or why there is none (a reason that names no server path, with its code
 * and params for the app: scene.mesh_not_local, scene.mesh_no_package {package}, scene.mesh_scheme {scheme}).
 * @param {string} filename as the URDF gives it
 * @param {string} baseDir what a relative filename is relative to (the URDF file's directory)
 * @param {string} rosPackagePath
 * @returns {{file: string} | {error: string, code: string, params?: Record<string, string>}}
 */
export function meshPath(filename, baseDir, rosPackagePath) {
  const f = filename.trim();
  if (/^file:/i.test(f)) {
    try {
      return { file: fileURLToPath(f) };
    } catch {
      return { error: 'not a file:// URI of this computer', code: 'scene.mesh_not_local' };
    }
  }
  const pkg = /^package:\/\/([^/]+)\/(.+)$/i.exec(f);
  if (pkg) {
    const dir = findPackage(pkg[1], rosPackagePath);
    return dir ? { file: path.join(dir, pkg[2]) } : { error: `the package "${pkg[1]}" is not on ROS_PACKAGE_PATH`, code: 'scene.mesh_no_package', params: { package: pkg[1] } };
  }
  const scheme = /^([a-z][a-z0-9+.-]*):\/\//i.exec(f);
  if (scheme) return { error: `${scheme[1]}:// URIs are not served`, code: 'scene.mesh_scheme', params: { scheme: scheme[1] } };
  return { file: path.resolve(baseDir, f) };
}
