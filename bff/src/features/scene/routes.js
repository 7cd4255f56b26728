// HTTP API of the scene page: /api/scene/... (session + page 'scene' required). An arm's URDF with its mesh
// filenames rewritten to this API, and the mesh files it references. Bad input and a dead ROS side get a 4xx with a
// clear message (the master down: 409), never a 5xx.
import fs from 'node:fs';
import fsp from 'node:fs/promises';
import path from 'node:path';
import { Router } from 'express';
import { CellConfigError } from '../../core/config/cell.js';
import { errorBody, httpError } from '../../core/http/errors.js';
import { armSpecs, urdfPath, urdfFileProblems } from './arms.js';
import { SceneError, MAX_URDF_BYTES, getParam, prepareUrdf, etagOf, meshPath, meshType, isMeshFile } from './urdf.js';

/** How long a browser may keep a mesh without asking again (the URL changes with the URDF's mesh list). */
const MESH_MAX_AGE_S = 86400;

/**
 * @param {{section: any, cell: import('../../core/config/cell-types.js').Cell, cellFile: string,
 *   env: import('../../core/config/env.js').Env, guard: import('express').RequestHandler[], log?: (m: string) => void,
 *   rosPackagePath?: () => string, timeoutMs?: number}} deps
 *   cellFile: relative `urdf` paths are relative to its directory (checked here, at start: CellConfigError).
 *   rosPackagePath: where package:// meshes are looked up (default: the process's ROS_PACKAGE_PATH, read per request).
 */
export function sceneRoutes({ section, cell, cellFile, env, guard, log = (m) => console.log(`[bff] ${m}`),
  rosPackagePath = () => process.env.ROS_PACKAGE_PATH || '', timeoutMs }) {
  const cellDir = path.dirname(path.resolve(cellFile));
  const missing = section ? urdfFileProblems(section, cellDir) : [];
  if (missing.length) throw new CellConfigError(cellFile, missing);
  const arms = new Map(armSpecs(section, cell).map((a) => [a.group, a]));
  // Files the BFF keeps to itself are never served as a mesh, whatever a URDF (a ROS parameter anyone on the ROS
  // graph may set) names.
  const privateDirs = [env.dataDir].map((d) => realpath(d));
  const privateFiles = new Set([env.usersFile, env.tlsKey].filter(Boolean).map((f) => realpath(f)));
  /** The meshes of each group's last URDF read, and what their relative filenames are relative to. */
  /** @type {Map<string, {meshes: import('./urdf.js').MeshRef[], baseDir: string}>} */
  const known = new Map();
  /** @type {Map<string, Promise<string>>} */
  const reading = new Map();

  /** @param {import('express').Request} req */
  const armOf = (req) => {
    const arm = arms.get(param(req, 'group'));
    if (!arm) {
      const group = param(req, 'group').slice(0, 64);
      const list = [...arms.keys()].join(', ');
      throw new SceneError(404, `no arm "${group}" in this cell's scene (arms: ${list || 'none'})`, 'scene.no_arm', { arm: group, arms: list });
    }
    return arm;
  };

  /** Read an arm's URDF from its source, check it, rewrite its meshes and remember them. @param {import('./arms.js').ArmSpec} arm */
  async function readUrdf(arm) {
    const src = arm.source;
    if (!src) throw new SceneError(404, `the arm "${arm.group}" has no URDF (scene.arms[].robot_description or urdf)`, 'scene.arm_no_urdf', { arm: arm.group });
    let text;
    let baseDir;
    let what;
    /** @type {{file: string} | {param: string}} for the errors' codes */
    let source;
    if (src.kind === 'file') {
      const file = urdfPath(src.file, cellDir);
      const name = path.basename(src.file); // its name, not where it lies
      what = `the URDF file ${name}`;
      source = { file: name };
      try {
        const st = await fsp.stat(file);
        if (!st.isFile()) throw Object.assign(new Error('not a file'), { code: 'EISDIR' });
        if (st.size > MAX_URDF_BYTES) throw new SceneError(422, `${what} is larger than ${MAX_URDF_BYTES} bytes`, 'scene.file_too_large', { file: name, limit: MAX_URDF_BYTES });
        text = await fsp.readFile(file, 'utf8');
      } catch (e) {
        if (e instanceof SceneError) throw e;
        const reason = e.code || 'error';
        throw new SceneError(404, `${what} (${src.field}) cannot be read (${reason})`, 'scene.file_unreadable', { file: name, field: src.field, reason });
      }
      baseDir = path.dirname(file);
    } else {
      what = `the parameter ${src.name}`;
      source = { param: src.name };
      const value = await getParam(env.rosMasterUri, src.name, { timeoutMs });
      if (typeof value !== 'string') {
        throw new SceneError(422, `${what} does not hold a URDF: it holds ${describeValue(value)}, not a string`, 'scene.param_not_string', { param: src.name });
      }
      text = value;
      // A URDF from a parameter has no file: its relative mesh paths are taken from the cell file's directory.
      baseDir = cellDir;
    }
    const out = prepareUrdf(text, arm.group, what, source);
    known.set(arm.group, { meshes: out.meshes, baseDir });
    return out.text;
  }

  /** One read at a time per group: concurrent requests share it. @param {import('./arms.js').ArmSpec} arm */
  const urdfOf = (arm) => {
    let p = reading.get(arm.group);
    if (!p) {
      p = readUrdf(arm).finally(() => reading.delete(arm.group));
      reading.set(arm.group, p);
    }
    return p;
  };

  const r = Router();
  r.get('/api/scene/arms/:group/urdf', ...guard, async (req, res) => {
    try {
      const text = await urdfOf(armOf(req));
      // Revalidated at every visit: a 304 while the URDF is the same.
      res.setHeader('Cache-Control', 'no-cache');
      res.setHeader('ETag', etagOf(text));
      res.type('application/xml');
      res.send(text);
    } catch (e) {
      sendError(res, e, log);
    }
  });

  r.get('/api/scene/arms/:group/meshes/:i/:name', ...guard, async (req, res) => {
    try {
      const arm = armOf(req);
      const i = param(req, 'i');
      const name = param(req, 'name');
      const noMesh = () => new SceneError(404, `the URDF of the arm "${arm.group}" has no mesh ${i.slice(0, 16)} named ${name.slice(0, 255)}`,
        'scene.no_mesh', { arm: arm.group, index: i.slice(0, 16), name: name.slice(0, 255) });
      if (!/^(0|[1-9][0-9]{0,5})$/.test(i)) throw noMesh();
      if (!known.has(arm.group)) await urdfOf(arm);
      const { meshes, baseDir } = known.get(arm.group);
      const mesh = meshes[Number(i)];
      if (!mesh || mesh.name !== name) throw noMesh();
      // Only mesh formats the view draws: a URDF (any node may set the parameter) must not make the BFF a file server.
      if (!isMeshFile(mesh.name)) throw new SceneError(404, `the mesh ${mesh.name} is not served: only .stl, .dae and .obj meshes are`, 'scene.mesh_format', { name: mesh.name });
      const where = meshPath(mesh.filename, baseDir, rosPackagePath());
      if ('error' in where) throw new SceneError(404, `the mesh ${mesh.name} cannot be read: ${where.error}`, where.code, { name: mesh.name, ...where.params });
      const real = realpath(where.file);
      if (privateFiles.has(real) || privateDirs.some((d) => real === d || real.startsWith(d + path.sep))) {
        throw new SceneError(404, `the mesh ${mesh.name} cannot be read: it lies among the BFF's own files`, 'scene.mesh_private', { name: mesh.name });
      }
      res.sendFile(real, {
        dotfiles: 'allow', // meshes may live under a hidden directory (a venv's pybullet_data, ~/.ros)
        headers: { 'Content-Type': meshType(mesh.name), 'Cache-Control': `private, max-age=${MESH_MAX_AGE_S}` },
      }, (err) => {
        if (!err || res.headersSent) return;
        const reason = /** @type {any} */ (err).code || 'not a file';
        sendError(res, new SceneError(404, `the mesh ${mesh.name} cannot be read (${reason})`, 'scene.mesh_unreadable', { name: mesh.name, reason }), log);
      });
    } catch (e) {
      sendError(res, e, log);
    }
  });
  return r;
}

/** Express 5 types a path parameter as string | string[]; ours are single segments. @param {import('express').Request} req @param {string} k */
const param = (req, k) => String(req.params[k]);

/** The path with its symbolic links resolved, or as given when it does not exist. @param {string} p */
function realpath(p) {
  try {
    return fs.realpathSync(p);
  } catch {
    return path.resolve(p);
  }
}

/** What a parameter holds, for a message. @param {unknown} v */
function describeValue(v) {
  if (v === null) return 'nothing';
  if (Array.isArray(v)) return 'a list';
  if (typeof v === 'object') return 'a namespace (a dictionary of parameters)';
  return `a ${typeof v}`;
}

/** @param {import('express').Response} res @param {unknown} e @param {(m: string) => void} log */
function sendError(res, e, log) {
  if (res.headersSent) return;
  // No cache headers of a success (the /api default) and the JSON content type.
  res.setHeader('Cache-Control', 'no-store');
  res.removeHeader('ETag');
  res.removeHeader('Content-Type');
  if (e instanceof SceneError) return res.status(e.status).json(e.code ? errorBody(e.message, e.code, e.params) : { error: e.message });
  const h = httpError(e);
  if (h.clientError) return res.status(h.status).json(h.code ? errorBody(h.message, h.code, h.params) : { error: h.message });
  log(`scene: ${/** @type {any} */ (e)?.stack || e}`);
  res.status(500).json({ error: 'internal error' });
}

/**
 * OpenAPI 3.1 path objects for these routes; the core adds what it answers around them (401, 403 page, 400 path
 * parameters, 405).
 */
export const sceneOpenApiPaths = (() => {
  const json = (schema) => ({ content: { 'application/json': { schema } } });
  // code and params: a stable code ("scene.param_unset") and the values in the message, for the app to say in the user's language.
  const error = { type: 'object', required: ['error'], properties: { error: { type: 'string' }, code: { type: 'string' }, params: { type: 'object' } } };
  const err = (description) => ({ description, ...json(error) });
  const group = { name: 'group', in: 'path', required: true, description: 'An arm of the scene section (scene.arms[].group)', schema: { type: 'string', pattern: '^[a-z][a-z0-9_]*$' } };
  const etag = { ETag: { description: 'Validator for If-None-Match', schema: { type: 'string' } } };
  const binary = { schema: { type: 'string', format: 'binary' } };
  return {
    '/api/scene/arms/{group}/urdf': {
      get: {
        summary: "An arm's URDF, its mesh filenames rewritten to /api/scene/arms/{group}/meshes/{i}/{name}", security: [{ session: [] }],
        parameters: [group],
        responses: {
          200: {
            description: 'The URDF (Cache-Control: no-cache; revalidate with If-None-Match)',
            headers: { ...etag, 'Cache-Control': { description: 'no-cache', schema: { type: 'string' } } },
            content: { 'application/xml': { schema: { type: 'string' } } },
          },
          304: { description: 'Not modified: the URDF still has the ETag sent in If-None-Match' },
          404: err("Unknown arm; the URDF file cannot be read; or the URDF parameter is not set (the arm's driver is not up)"),
          409: err('The ROS master does not answer: the URDF parameter cannot be read'),
          422: err('The parameter or file does not hold a URDF (not a string, not a <robot> XML document, too large)'),
        },
      },
    },
    '/api/scene/arms/{group}/meshes/{i}/{name}': {
      get: {
        summary: "A mesh file an arm's URDF references (the URL the URDF route gave it)", security: [{ session: [] }],
        parameters: [
          group,
          { name: 'i', in: 'path', required: true, description: "The mesh's number in the URDF's list of distinct mesh filenames", schema: { type: 'integer', minimum: 0 } },
          { name: 'name', in: 'path', required: true, description: "The mesh file's base name, as in that URL", schema: { type: 'string' } },
        ],
        responses: {
          200: {
            description: 'The mesh file (Cache-Control: private, max-age=86400)',
            headers: { ...etag, 'Cache-Control': { description: 'private, max-age=86400', schema: { type: 'string' } } },
            content: { 'model/stl': binary, 'model/vnd.collada+xml': binary, 'model/obj': binary, 'application/octet-stream': binary },
          },
          304: { description: 'Not modified: the file still has the ETag sent in If-None-Match' },
          404: err('Unknown arm or mesh, or the mesh file cannot be read'),
          409: err('The mesh list is not known yet and the ROS master does not answer: the URDF parameter cannot be read'),
          422: err('The parameter or file does not hold a URDF'),
        },
      },
    },
  };
})();
