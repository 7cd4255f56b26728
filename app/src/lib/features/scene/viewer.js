/**
 * The 3D view itself (three.js, urdf-loader): loaded lazily by Scene3D.svelte, so no other page carries three.js.
 * It draws on demand (a change, a camera move, a resize) and only while its canvas is on screen and the app
 * is visible.
 */
import * as THREE from 'three';
import { OrbitControls } from 'three/examples/jsm/controls/OrbitControls.js';
import { STLLoader } from 'three/examples/jsm/loaders/STLLoader.js';
import { ColladaLoader } from 'three/examples/jsm/loaders/ColladaLoader.js';
import { OBJLoader } from 'three/examples/jsm/loaders/OBJLoader.js';
import URDFLoader from 'urdf-loader';
import { presetPose, frameCap } from './logic.js';
import { themeColor, onThemeChange } from '../../core/theme-colors.js';
import { m } from '$lib/paraglide/messages.js';

const STALE_COLOR = new THREE.Color(0x8a8f98);
const GHOST_COLOR = new THREE.Color(0xf59e0b);
const PATH_COLOR = new THREE.Color(0x7c3aed);
const FOV = 45;
const MIN_CHANGE = 1e-4;
const VSYNC_SLACK_MS = 8;

/**
 * The same colour without specular or physically based shading: per pixel the cheapest lit material, which matters
 * where WebGL runs in software (phones' fallbacks, hosts without a GPU). @param {any} m
 */
function matte(m) {
  if (!m || m.isMeshLambertMaterial || m.isMeshBasicMaterial || !m.color) return m;
  const out = new THREE.MeshLambertMaterial({ color: m.color, transparent: m.transparent, opacity: m.opacity, side: m.side });
  out.name = m.name;
  m.dispose();
  return out;
}

/** @template {THREE.Object3D} T @param {T} root @returns {T} */
function matteAll(root) {
  root.traverse((/** @type {any} */ o) => {
    if (o.isMesh) o.material = Array.isArray(o.material) ? o.material.map(matte) : matte(o.material);
  });
  return root;
}

/** @typedef {import('./tf.js').Pose} Pose */

/** Put an object at a pose of the view's frame, or hide it (null). @param {THREE.Object3D} obj @param {Pose | null} pose */
function place(obj, pose) {
  obj.visible = !!pose;
  if (!pose) return;
  obj.position.fromArray(pose.p);
  obj.quaternion.fromArray(pose.q);
}

/** Whether this browser can draw WebGL at all. */
export function webglAvailable() {
  try {
    const c = document.createElement('canvas');
    return !!(window.WebGLRenderingContext && (c.getContext('webgl2') || c.getContext('webgl')));
  } catch {
    return false;
  }
}

/**
 * @typedef {{ robot: any, stale: boolean, originals: Map<any, any>, ghost?: boolean }} ArmEntry
 */

export class SceneViewer {
  /**
   * @param {HTMLElement} host  the element the canvas fills
   * @param {{ onMeshError?: (group: string, file: string) => void, label?: string }} [o]
   */
  constructor(host, o = {}) {
    this.host = host;
    this.onMeshError = o.onMeshError ?? (() => {});
    // No multisampling: on a phone's GPU (or a software renderer) it costs more than the edges are worth.
    this.renderer = new THREE.WebGLRenderer({ antialias: false, powerPreference: 'low-power' });
    // At most 1.5 device pixels per CSS pixel: sharp enough, and a phone's GPU (or a software renderer) keeps up.
    this.renderer.setPixelRatio(Math.min(window.devicePixelRatio || 1, 1.5));
    const canvas = this.renderer.domElement;
    canvas.setAttribute('role', 'img');
    canvas.setAttribute('aria-label', o.label ?? m.scene_title_cell());
    canvas.style.display = 'block';
    canvas.style.touchAction = 'none';
    host.appendChild(canvas);

    this.scene = new THREE.Scene();
    this.camera = new THREE.PerspectiveCamera(FOV, 1, 0.01, 100);
    this.camera.up.set(0, 0, 1); // ROS: z up
    this.scene.add(new THREE.HemisphereLight(0xffffff, 0x667080, 2.2));
    const sun = new THREE.DirectionalLight(0xffffff, 1.6);
    sun.position.set(2, -1.5, 3);
    this.scene.add(sun);
    // The floor (the cell frame's xy plane, 0.1 m grid) and the cell frame's axes (x red, y green, z blue).
    /** @type {THREE.GridHelper | null} */
    this.grid = null;
    this.applyTheme();
    this.stopTheme = onThemeChange(() => {
      this.applyTheme();
      this.invalidate();
    });
    this.scene.add(new THREE.AxesHelper(0.25));
    /** @type {Map<string, ArmEntry>} */
    this.arms = new Map();
    /** @type {Map<string, THREE.Mesh>} */
    this.shapes = new Map();
    /** @type {Map<string, { text: string, pose: Pose | null }>} where each arm's base is drawn */
    this.urdfs = new Map();
    /** @type {Map<string, any>} the target ghost of each arm, when there is one */
    this.ghosts = new Map();
    /** @type {THREE.Group | null} a routine's path */
    this.path = null;

    this.controls = new OrbitControls(this.camera, canvas);
    // One finger orbits, two pan and pinch-zoom (OrbitControls' touch defaults, stated here on purpose).
    this.controls.touches = { ONE: THREE.TOUCH.ROTATE, TWO: THREE.TOUCH.DOLLY_PAN };
    this.controls.enableDamping = false;
    this.controls.addEventListener('change', () => this.invalidate());
    // Once the user turns the camera, the view no longer re-frames itself when the content changes.
    this.userMoved = false;
    this.controls.addEventListener('start', () => { this.userMoved = true; });

    this.frames = 0;
    this.visible = true;
    this.raf = 0;
    /** @type {any} a frame put off to keep to the frame cap */
    this.wait = 0;
    this.coarse = window.matchMedia?.('(pointer: coarse)').matches ?? false;
    /** a frame's mean cost in ms (the render call, exponentially averaged) */
    this.frameMs = 0;
    this.lastFrame = -Infinity;
    this.disposed = false;
    this.resize = new ResizeObserver(() => this.fit());
    this.resize.observe(host);
    this.onScreen = new IntersectionObserver((entries) => {
      this.visible = entries.some((e) => e.isIntersecting);
      this.invalidate();
    });
    this.onScreen.observe(host);
    this.onVisibility = () => this.invalidate();
    document.addEventListener('visibilitychange', this.onVisibility);
    this.fit();
    this.preset('front');
  }

  fit() {
    const w = Math.max(1, this.host.clientWidth);
    const h = Math.max(1, this.host.clientHeight);
    this.renderer.setSize(w, h, false);
    this.renderer.domElement.style.width = '100%';
    this.renderer.domElement.style.height = '100%';
    this.camera.aspect = w / h;
    this.camera.updateProjectionMatrix();
    this.invalidate();
  }

  /**
   * Draw at the next frame (once, however many changes come before it), if the view is on screen; at most
   * frameCap() frames a second, so a moving arm leaves the page (its controls, its heartbeats) time to run.
   */
  invalidate() {
    if (this.disposed || this.raf || this.wait || !this.visible || document.visibilityState === 'hidden') return;
    // Half a display frame of slack: at 60 Hz and a cap of 30 the view draws every other vsync, a steady 30 frames a
    // second (without it a frame due a hair after a vsync waits for the next one: 20-25 a second).
    const fps = frameCap({ coarse: this.coarse, frameMs: this.frameMs });
    const early = this.lastFrame + 1000 / fps - VSYNC_SLACK_MS - performance.now();
    if (early > 1) {
      this.wait = setTimeout(() => {
        this.wait = 0;
        this.invalidate();
      }, early);
      return;
    }
    this.raf = requestAnimationFrame(() => {
      this.raf = 0;
      if (this.disposed) return;
      const t0 = performance.now();
      this.lastFrame = t0;
      this.renderer.render(this.scene, this.camera);
      const cost = performance.now() - t0;
      // The first frame compiles the shaders: not what the next ones cost.
      if (this.frames) this.frameMs = 0.9 * this.frameMs + 0.1 * cost;
      this.frames++;
    });
  }

  /**
   * Add an arm from its URDF text, its base placed at `pose` in the view's frame (null: not known yet, e.g. TF has
   * not said; the arm is hidden until setBase places it).
   * @param {string} group @param {string} urdf @param {Pose | null} pose
   * @returns {any} the URDF robot (its joints by name)
   */
  addArm(group, urdf, pose) {
    const robot = this.#load(group, urdf);
    place(robot, pose);
    this.scene.add(robot);
    this.arms.set(group, { robot, stale: false, originals: new Map() });
    this.urdfs.set(group, { text: urdf, pose });
    this.frameAll();
    return robot;
  }

  /**
   * Move an arm's base (TF moved it, or first placed it; null: hide it), with its ghost and path.
   * @param {string} group @param {Pose | null} pose
   */
  setBase(group, pose) {
    const src = this.urdfs.get(group);
    const arm = this.arms.get(group);
    if (!src || !arm) return;
    const was = src.pose;
    if (was && pose && [...was.p, ...was.q].every((v, i) => Math.abs(v - [...pose.p, ...pose.q][i]) < MIN_CHANGE)) return;
    src.pose = pose;
    place(arm.robot, pose);
    const ghost = this.ghosts.get(group);
    if (ghost) place(ghost, pose);
    if (this.path && this.path.userData.group === group) place(this.path, pose);
    if (!was) this.frameAll();
    this.invalidate();
  }

  /** Where an arm's base is drawn (null: not placed). @param {string} group @returns {Pose | null} */
  basePose(group) {
    return this.urdfs.get(group)?.pose ?? null;
  }

  /** @param {string} group @param {string} urdf */
  #load(group, urdf) {
    const manager = new THREE.LoadingManager();
    manager.onLoad = () => {
      for (const g of this.ghosts.values()) g.traverse(g.userData.glassy);
      this.invalidate();
    };
    const loader = new URDFLoader(manager);
    loader.parseCollision = false;
    loader.loadMeshCb = (/** @type {string} */ path, /** @type {THREE.LoadingManager} */ m, /** @type {THREE.Material} */ material, /** @type {(o: any, e?: Error) => void} */ done) => {
      const ext = path.split('?')[0].split('.').pop()?.toLowerCase();
      const fail = (/** @type {any} */ e) => {
        this.onMeshError(group, decodeURIComponent(path.split('/').pop() ?? path));
        done(null, e instanceof Error ? e : new Error(String(e)));
      };
      if (ext === 'stl') {
        new STLLoader(m).load(path, (geom) => done(new THREE.Mesh(geom, matte(material))), undefined, fail);
      } else if (ext === 'dae') {
        new ColladaLoader(m).load(path, (dae) => done(dae?.scene ? matteAll(dae.scene) : null), undefined, fail);
      } else if (ext === 'obj') {
        new OBJLoader(m).load(path, (obj) => {
          const mat = matte(material);
          obj.traverse((c) => { if (/** @type {any} */ (c).isMesh) /** @type {any} */ (c).material = mat; });
          done(obj);
        }, undefined, fail);
      } else {
        fail(new Error(`unsupported mesh format .${ext}`));
      }
    };
    const robot = matteAll(loader.parse(urdf));
    // Draw the joints as reported, even past a limit the URDF states.
    for (const j of Object.values(robot.joints)) /** @type {any} */ (j).ignoreLimits = true;
    return robot;
  }

  /**
   * @param {string} group @param {Record<string, number>} values joint name -> position (rad or m)
   * @returns {boolean} whether anything moved
   */
  setJoints(group, values) {
    const arm = this.arms.get(group);
    if (!arm) return false;
    let moved = false;
    for (const [name, v] of Object.entries(values)) {
      const j = arm.robot.joints[name];
      // Below a tenth of a milliradian (or millimetre) nothing visible moves: no frame for a standing arm's noise.
      if (j && Math.abs(Number(j.angle) - v) >= MIN_CHANGE && j.setJointValue(v)) moved = true;
    }
    if (moved) this.invalidate();
    return moved;
  }

  /**
   * Show where a move would take the arm: a translucent copy of it at the target joints (null: none).
   * @param {string} group @param {Record<string, number> | null} values
   */
  setGhost(group, values) {
    let ghost = this.ghosts.get(group);
    if (!values) {
      if (ghost) {
        this.scene.remove(ghost);
        ghost.traverse((/** @type {any} */ o) => { if (o.isMesh) o.material.dispose(); });
        this.ghosts.delete(group);
        this.invalidate();
      }
      return;
    }
    const src = this.urdfs.get(group);
    if (!src) return;
    if (!ghost) {
      ghost = this.#load(group, src.text);
      place(ghost, src.pose);
      // Meshes load later: each one that arrives is made see-through as well.
      const glassy = (/** @type {any} */ o) => {
        if (!o.isMesh || o.userData.ghost) return;
        o.userData.ghost = true;
        o.material = new THREE.MeshLambertMaterial({ color: GHOST_COLOR, transparent: true, opacity: 0.35, depthWrite: false });
      };
      ghost.traverse(glassy);
      ghost.userData.glassy = glassy;
      this.ghosts.set(group, ghost);
      this.scene.add(ghost);
    }
    for (const [name, v] of Object.entries(values)) ghost.joints[name]?.setJointValue(v);
    ghost.traverse(ghost.userData.glassy);
    this.invalidate();
  }

  /**
   * Draw a path of TCP positions given in the base frame of an arm (a routine's recorded poses), or none.
   * @param {string | null} group @param {number[][]} points
   */
  setPath(group, points) {
    if (this.path) {
      this.scene.remove(this.path);
      this.path.traverse((/** @type {any} */ o) => { o.geometry?.dispose(); o.material?.dispose(); });
      this.path = null;
    }
    const src = group ? this.urdfs.get(group) : null;
    if (src && points.length) {
      const path = new THREE.Group();
      path.userData.group = group;
      place(path, src.pose);
      const vs = points.map((p) => new THREE.Vector3(p[0], p[1], p[2]));
      path.add(new THREE.Line(new THREE.BufferGeometry().setFromPoints(vs), new THREE.LineBasicMaterial({ color: PATH_COLOR })));
      for (const v of vs) {
        const dot = new THREE.Mesh(new THREE.SphereGeometry(0.008, 12, 8), new THREE.MeshLambertMaterial({ color: PATH_COLOR }));
        dot.position.copy(v);
        path.add(dot);
      }
      this.path = path;
      this.scene.add(path);
    }
    this.invalidate();
  }

  /** The joint values the ghost of an arm is drawn at (none: no ghost). @param {string} group @param {string[]} names */
  ghostJoints(group, names) {
    const g = this.ghosts.get(group);
    /** @type {Record<string, number>} */
    const out = {};
    if (g) for (const n of names) if (g.joints[n]) out[n] = Number(g.joints[n].angle);
    return out;
  }

  /** The joint values the view draws (what the tests compare with /joint_states). @param {string} group @param {string[]} names */
  drawnJoints(group, names) {
    const arm = this.arms.get(group);
    /** @type {Record<string, number>} */
    const out = {};
    for (const n of names) {
      const j = arm?.robot.joints[n];
      if (j) out[n] = Number(j.angle);
    }
    return out;
  }

  /** Grey the arm out (its joint states are old) or give it its colours back. @param {string} group @param {boolean} stale */
  setStale(group, stale) {
    const arm = this.arms.get(group);
    if (!arm || arm.stale === stale) return;
    arm.stale = stale;
    arm.robot.traverse((/** @type {any} */ o) => {
      if (!o.isMesh) return;
      if (stale) {
        arm.originals.set(o, o.material);
        const grey = (Array.isArray(o.material) ? o.material[0] : o.material).clone();
        grey.color?.copy(STALE_COLOR);
        grey.transparent = true;
        grey.opacity = 0.55;
        o.material = grey;
      } else if (arm.originals.has(o)) {
        o.material = arm.originals.get(o);
      }
    });
    if (!stale) arm.originals.clear();
    this.invalidate();
  }

  /** Show the shapes (markers) given, by key; others are removed. @param {Iterable<import('./logic.js').Shape>} list */
  setShapes(list) {
    const keep = new Set();
    let changed = false;
    for (const s of list) {
      keep.add(s.key);
      let mesh = this.shapes.get(s.key);
      if (!mesh || mesh.userData.shape !== s.shape) {
        if (mesh) this.#drop(mesh);
        const geom = s.shape === 'sphere' ? new THREE.SphereGeometry(0.5, 20, 14)
          : s.shape === 'cylinder' ? new THREE.CylinderGeometry(0.5, 0.5, 1, 24).rotateX(Math.PI / 2) // ROS: along z
            : new THREE.BoxGeometry(1, 1, 1);
        mesh = new THREE.Mesh(geom, new THREE.MeshLambertMaterial());
        mesh.userData.shape = s.shape;
        this.shapes.set(s.key, mesh);
        this.scene.add(mesh);
        changed = true;
      }
      // A part lying still (its pose noise below MIN_CHANGE) needs no new frame.
      const same = mesh.userData.last && [...s.position, ...s.quaternion, ...s.scale, ...s.color]
        .every((v, i) => Math.abs(v - mesh.userData.last[i]) < MIN_CHANGE);
      if (same) continue;
      changed = true;
      mesh.userData.last = [...s.position, ...s.quaternion, ...s.scale, ...s.color];
      mesh.position.fromArray(s.position);
      mesh.quaternion.fromArray(s.quaternion);
      mesh.scale.fromArray(s.scale);
      const mat = /** @type {THREE.MeshLambertMaterial} */ (mesh.material);
      mat.color.setRGB(s.color[0], s.color[1], s.color[2]);
      mat.transparent = s.color[3] < 1;
      mat.opacity = s.color[3];
    }
    for (const [k, mesh] of this.shapes) if (!keep.has(k)) { this.#drop(mesh); this.shapes.delete(k); changed = true; }
    if (changed) this.invalidate();
  }

  /** @param {THREE.Mesh} mesh */
  #drop(mesh) {
    this.scene.remove(mesh);
    mesh.geometry.dispose();
    /** @type {THREE.Material} */ (mesh.material).dispose();
  }

  /** The sphere around everything the cell shows (arms and shapes). */
  bounds() {
    const box = new THREE.Box3();
    for (const a of this.arms.values()) if (a.robot.visible) box.expandByObject(a.robot);
    for (const m of this.shapes.values()) box.expandByObject(m);
    if (box.isEmpty()) box.set(new THREE.Vector3(-0.5, -0.5, 0), new THREE.Vector3(0.5, 0.5, 0.8));
    const sphere = box.getBoundingSphere(new THREE.Sphere());
    return { center: sphere.center.toArray(), radius: sphere.radius };
  }

  /** Remember the frame of the whole cell (the presets and Reset view use it); re-aim unless the user moved the camera. */
  frameAll() {
    this.home = this.bounds();
    if (!this.userMoved) this.preset(this.lastPreset ?? 'front');
  }

  /** @param {'front' | 'top' | 'side'} name */
  preset(name) {
    this.lastPreset = name;
    const b = this.home ?? this.bounds();
    const p = presetPose(name, b.center, b.radius, FOV, this.camera.aspect);
    this.camera.position.fromArray(p.position);
    this.controls.target.fromArray(p.target);
    this.controls.update();
    this.invalidate();
  }

  resetView() {
    this.userMoved = false;
    this.frameAll();
    this.preset('front');
  }

  /** The background and the floor grid in the drawn theme's colours (app.css --scene-*). */
  applyTheme() {
    const bg = new THREE.Color(themeColor('--scene-bg', '#e9edf2'));
    this.renderer.setClearColor(bg);
    this.scene.background = bg;
    if (this.grid) {
      this.scene.remove(this.grid);
      this.grid.geometry.dispose();
      /** @type {THREE.Material} */ (this.grid.material).dispose();
    }
    // The floor: the cell frame's xy plane, 0.1 m grid.
    this.grid = new THREE.GridHelper(4, 40, new THREE.Color(themeColor('--scene-grid', '#9aa3ad')), new THREE.Color(themeColor('--scene-grid-2', '#c8ced6')));
    this.grid.rotation.x = Math.PI / 2;
    this.scene.add(this.grid);
  }

  dispose() {
    this.stopTheme();
    this.disposed = true;
    if (this.raf) cancelAnimationFrame(this.raf);
    if (this.wait) clearTimeout(this.wait);
    this.resize.disconnect();
    this.onScreen.disconnect();
    document.removeEventListener('visibilitychange', this.onVisibility);
    this.controls.dispose();
    this.scene.traverse((/** @type {any} */ o) => {
      o.geometry?.dispose?.();
      for (const m of [o.material].flat()) m?.dispose?.();
    });
    this.renderer.dispose();
    this.renderer.domElement.remove();
  }
}
