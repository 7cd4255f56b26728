/**
 * Where the next move would take the arm (the Manual page's move panel asks the driver, /cell/manual/preview_move),
 * for the 3D view to draw as a ghost. One at a time: the move the user is setting up.
 */
import { localized } from '../../core/said.js';

/**
 * @typedef {{ group: string, kind: 'named' | 'relative' | 'pose', reachable: boolean, message: string,
 *   positions: Record<string, number> | null, tcpPose: number[] | null }} MovePreview
 */

export const PREVIEW = Object.freeze({ service: '/cell/manual/preview_move', type: 'cell_msgs/PreviewMove' });

class PreviewStore {
  /** @type {MovePreview | null} */
  current = $state(null);

  /** @param {MovePreview | null} p */
  set(p) {
    this.current = p;
  }

  clear() {
    this.current = null;
  }
}

export const movePreview = new PreviewStore();

/**
 * The preview from the driver's answer.
 * @param {string} group @param {'named' | 'relative' | 'pose'} kind @param {any} r cell_msgs/PreviewMove response
 * @returns {MovePreview}
 */
export function previewFrom(group, kind, r) {
  r = localized(r);
  const names = Array.isArray(r?.joint_names) ? r.joint_names : [];
  const pos = Array.isArray(r?.positions) ? r.positions : [];
  const reachable = r?.reachable === true && names.length > 0 && names.length === pos.length;
  /** @type {Record<string, number>} */
  const positions = {};
  names.forEach((/** @type {string} */ n, /** @type {number} */ i) => { positions[n] = Number(pos[i]); });
  return {
    group, kind, reachable,
    message: typeof r?.message === 'string' ? r.message : '',
    positions: reachable ? positions : null,
    tcpPose: reachable && Array.isArray(r?.tcp_pose) ? r.tcp_pose.map(Number) : null,
  };
}
