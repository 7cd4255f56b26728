// Which UR controller moves each motion group: one rule, implemented once per language. The ROS side has it as
// cell_nodes.manual.config.resolve_hosts (same order, same errors); scripts/stack.js uses this one to start one
// simulated controller per host.
//
//   1. the environment variable UR_HOSTS (`<group>=<host>[,<group>=<host>...]`), per group: several stacks of one
//      cell run side by side with their own controller addresses;
//   2. else the group's `host` in the cell file (manual.groups[].host);
//   3. else the environment variable UR_HOST, else 127.0.0.1.
// Groups whose resolved hosts are equal belong to the same arm (one driver instance, one controller connection).

export const DEFAULT_UR_HOST = '127.0.0.1';

// An IPv4 address or a host name (its last label not all digits): config/features/manual.schema.json's pattern.
const HOST = /^(?:((25[0-5]|2[0-4][0-9]|1[0-9][0-9]|[1-9]?[0-9])\.){3}(25[0-5]|2[0-4][0-9]|1[0-9][0-9]|[1-9]?[0-9])|(?=.{1,253}$)([A-Za-z0-9]([A-Za-z0-9-]{0,61}[A-Za-z0-9])?\.)*(?![0-9]+$)[A-Za-z0-9]([A-Za-z0-9-]{0,61}[A-Za-z0-9])?)$/;

/** @param {unknown} v @returns {boolean} */
export const isHost = (v) => typeof v === 'string' && HOST.test(v);

/** UR_HOST, else 127.0.0.1. @param {Record<string, string | undefined>} env */
export const defaultHost = (env) => String(env.UR_HOST ?? '').trim() || DEFAULT_UR_HOST;

/**
 * UR_HOSTS parsed, in order: [group, host]. Blank entries are skipped; an entry that is not `<group>=<host>` is an
 * error (a typo must not quietly send a group to the default controller).
 * @param {string | undefined} text
 * @returns {[string, string][]}
 */
export function parseUrHosts(text) {
  /** @type {[string, string][]} */
  const out = [];
  for (const raw of String(text ?? '').split(',')) {
    const entry = raw.trim();
    if (!entry) continue;
    const eq = entry.indexOf('=');
    const group = eq >= 0 ? entry.slice(0, eq).trim() : '';
    const host = eq >= 0 ? entry.slice(eq + 1).trim() : '';
    if (!group || !host) throw new Error(`UR_HOSTS: expected <group>=<host>[,<group>=<host>...], got '${entry}'`);
    out.push([group, host]);
  }
  return out;
}

/**
 * The controller address of every UR motion group (driver ur_rtde) of the cell file's manual section, in the
 * section's order (a ros_control group has none: the arm's own ROS driver owns its controller).
 * Throws (naming the field) for a bad group host, a bad UR_HOST that a group uses, a malformed UR_HOSTS, one
 * naming a group the cell does not have, or a bad host in it.
 * @param {{ groups?: { name: string, host?: string, driver?: string }[] } | undefined | null} manualSection
 * @param {Record<string, string | undefined>} [env] default process.env
 * @returns {Record<string, string>} group -> host
 */
export function resolveHosts(manualSection, env = process.env) {
  const fallback = defaultHost(env);
  /** @type {Record<string, string>} */
  const hosts = {};
  (manualSection?.groups ?? []).forEach((g, i) => {
    if (!g || typeof g !== 'object' || typeof g.name !== 'string') return;
    if (g.driver === 'ros_control') return; // its own ROS driver owns its controller: no UR host
    const host = g.host;
    if (host !== undefined && host !== null && !isHost(host)) {
      throw new Error(`manual.groups[${i}].host: expected a host name or an IPv4 address, got '${host}'`);
    }
    hosts[g.name] = host ?? fallback;
  });
  if (!isHost(fallback) && Object.values(hosts).includes(fallback)) {
    throw new Error(`UR_HOST: expected a host name or an IPv4 address, got '${fallback}'`);
  }
  for (const [group, host] of parseUrHosts(env.UR_HOSTS)) {
    if (!Object.hasOwn(hosts, group)) {
      throw new Error(`UR_HOSTS: '${group}' is not a motion group of this cell (manual.groups: ${Object.keys(hosts).join(', ') || 'none'})`);
    }
    if (!isHost(host)) throw new Error(`UR_HOSTS: ${group}=${host}: expected a host name or an IPv4 address`);
    hosts[group] = host;
  }
  return hosts;
}

/**
 * The arms: the distinct hosts (first appearance first), each with its groups in the section's order.
 * @param {Record<string, string>} hosts from resolveHosts
 * @returns {{ host: string, groups: string[] }[]}
 */
export function armsOf(hosts) {
  /** @type {Map<string, string[]>} */
  const by = new Map();
  for (const [group, host] of Object.entries(hosts)) {
    if (!by.has(host)) by.set(host, []);
    by.get(host)?.push(group);
  }
  return [...by].map(([host, groups]) => ({ host, groups }));
}
