// The environment contract of DESIGN.md, read in one place.
import path from 'node:path';
import { fileURLToPath } from 'node:url';

export const REPO_ROOT = path.resolve(path.dirname(fileURLToPath(import.meta.url)), '../../../..');

/**
 * @typedef {object} Env
 * @property {number} port HTTP port of the BFF
 * @property {number} tlsPort HTTPS port (used by the HTTPS issue)
 * @property {string} host address the BFF listens on
 * @property {string} rosMasterUri
 * @property {number} rosbridgePort rosbridge server on 127.0.0.1
 * @property {string} cellConfig path of the cell file
 * @property {string} dataDir runtime state
 * @property {string} usersFile
 * @property {string} appDir built PWA
 * @property {number} tokenTtlS session token lifetime
 * @property {string} usbRoots colon-separated USB mount roots (overrides the cell file)
 * @property {string} tlsCert user-provided certificate (PEM file), replaces the local CA's
 * @property {string} tlsKey its key
 * @property {{brokerUrl: string, cellUrl: string, username: string, password: string}} plant the plant broker's
 *   address and credentials (override the cell file's plant section; credentials never live in the cell file)
 */

/** @param {NodeJS.ProcessEnv} [e] @returns {Env} */
export function readEnv(e = process.env) {
  const dataDir = path.resolve(e.DATA_DIR || path.join(REPO_ROOT, '.data'));
  return {
    port: int(e.PORT, 8080),
    tlsPort: int(e.TLS_PORT, 8443),
    host: e.BFF_HOST || '0.0.0.0',
    rosMasterUri: e.ROS_MASTER_URI || 'http://127.0.0.1:11311',
    rosbridgePort: int(e.ROSBRIDGE_PORT, 9090),
    cellConfig: path.resolve(e.CELL_CONFIG || path.join(REPO_ROOT, 'config/demo-cell.yaml')),
    dataDir,
    usersFile: path.resolve(e.USERS_FILE || path.join(dataDir, 'users.json')),
    appDir: path.resolve(e.APP_DIR || path.join(REPO_ROOT, 'app/build')),
    tokenTtlS: int(e.SESSION_TTL_S, 30 * 60),
    usbRoots: e.USB_ROOTS || '',
    tlsCert: e.TLS_CERT || '',
    tlsKey: e.TLS_KEY || '',
    plant: {
      brokerUrl: e.PLANT_BROKER_URL || '', cellUrl: e.PLANT_CELL_URL || '',
      username: e.PLANT_MQTT_USERNAME || '', password: e.PLANT_MQTT_PASSWORD || '',
    },
  };
}

function int(v, dflt) {
  if (v === undefined || v === '') return dflt;
  const n = Number(v);
  if (!Number.isInteger(n) || n < 0 || n > 65535 * 1000) throw new Error(`not an integer: ${v}`);
  return n;
}
