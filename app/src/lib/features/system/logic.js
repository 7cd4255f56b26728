/**
 * System's plain logic: health rows and uptime text, and the expected refresh period of its values.
 */

/** /api/system is polled this often; its values are stale after two missed polls. */
export const POLL_MS = 3000;
export const STALE_AFTER_MS = 2 * POLL_MS + 1000;

/** @param {number} s */
export function uptimeText(s) {
  if (!Number.isFinite(s)) return '—';
  const d = Math.floor(s / 86400), h = Math.floor((s % 86400) / 3600), m = Math.floor((s % 3600) / 60);
  return d ? `${d} d ${h} h` : h ? `${h} h ${m} min` : `${m} min ${Math.floor(s % 60)} s`;
}

/**
 * @typedef {{ state: string, since: number, error: string }} PlantLink
 * @typedef {{ status: string, ros?: { rosbridge?: boolean, master?: boolean }, uptime_s: number, version: string,
 *   plant?: { broker: string, group_id: string, edge_node_id: string, reporting: PlantLink, view: PlantLink } }} Health
 * @param {Health | null | undefined} health
 * @param {boolean} offline  the BFF did not answer the last poll
 * @returns {{ label: string, ok: boolean, text: string }[]}
 */
export function healthRows(health, offline) {
  if (!health) return [];
  return [
    { label: 'BFF', ok: !offline && health.status === 'ok', text: offline ? 'unreachable' : health.status },
    { label: 'rosbridge', ok: !!health.ros?.rosbridge, text: health.ros?.rosbridge ? 'up' : 'down' },
    { label: 'ROS master', ok: !!health.ros?.master, text: health.ros?.master ? 'up' : 'down' },
    // The plant's broker (cell files with a plant section): this cell's report on it.
    ...(health.plant && health.plant.reporting.state !== 'off' ? [{
      label: `Plant broker ${health.plant.broker}`, ok: health.plant.reporting.state === 'connected',
      text: health.plant.reporting.state === 'down' && health.plant.reporting.error
        ? `down: ${health.plant.reporting.error}` : health.plant.reporting.state,
    }] : []),
  ];
}
