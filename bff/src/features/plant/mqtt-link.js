// The MQTT side shared by the edge node and the plant host: client options from the cell file and the environment,
// reconnection with back-off, and the link state the System page shows (logged once per change).
import fs from 'node:fs';
import path from 'node:path';
import mqtt from 'mqtt';

/** @typedef {{state: 'off'|'connecting'|'connected'|'down', since: number, error: string}} LinkState */

/**
 * Broker URL and client options. Credentials come from PLANT_MQTT_USERNAME / PLANT_MQTT_PASSWORD, else from the
 * file the section names (user on line 1, password on line 2), never from the cell file itself.
 * @param {any} section @param {{dataDir: string, plant: import('../../core/config/env.js').Env['plant']}} env
 */
export function brokerOptions(section, env) {
  const url = env.plant.brokerUrl || section.broker;
  /** @type {import('mqtt').IClientOptions} */
  const o = {};
  const file = (/** @type {string} */ f) => path.resolve(env.dataDir, f);
  if (section.credentials_file) {
    const [user = '', pass = ''] = fs.readFileSync(file(section.credentials_file), 'utf8').split(/\r?\n/);
    if (user) o.username = user;
    if (pass) o.password = pass;
  }
  if (env.plant.username) o.username = env.plant.username;
  if (env.plant.password) o.password = env.plant.password;
  const tls = section.tls || {};
  if (tls.ca_file) o.ca = fs.readFileSync(file(tls.ca_file));
  if (tls.cert_file) o.cert = fs.readFileSync(file(tls.cert_file));
  if (tls.key_file) o.key = fs.readFileSync(file(tls.key_file));
  if (tls.reject_unauthorized === false) o.rejectUnauthorized = false;
  return { url, options: o };
}

const FIRST_RETRY_MS = 1000;
const LAST_RETRY_MS = 30_000;

/**
 * An MQTT client that reconnects with back-off (1 s doubling to 30 s) and keeps a link state.
 * @param {object} o
 * @param {string} o.url
 * @param {import('mqtt').IClientOptions} o.options
 * @param {string} o.who for the log ("plant edge node", "plant view")
 * @param {(m: string) => void} o.log
 * @param {(s: LinkState) => void} [o.onState]
 * @param {typeof mqtt.connect} [o.connect]
 */
export function connectWithBackoff({ url, options, who, log, onState = () => {}, connect = mqtt.connect }) {
  /** @type {LinkState} */
  let state = { state: 'connecting', since: Date.now(), error: '' };
  /** @param {LinkState['state']} s @param {string} [error] */
  const set = (s, error = '') => {
    if (s === state.state && error === state.error) return;
    const was = state.state;
    state = { state: s, since: s === was ? state.since : Date.now(), error };
    if (s !== was) log(`${who}: broker ${url} ${s}${error ? `: ${error}` : ''}`);
    onState(state);
  };
  // A refused login is retried too (the plant's admin may fix the broker's users without restarting the cell).
  const client = connect(url, { reconnectPeriod: FIRST_RETRY_MS, connectTimeout: 5000, reconnectOnConnackError: true, ...options });
  client.on('connect', () => {
    client.options.reconnectPeriod = FIRST_RETRY_MS;
    set('connected');
  });
  client.on('error', (e) => set('down', e?.message || String(e)));
  client.on('close', () => {
    if (state.state === 'connected') set('down', 'connection lost');
    else if (state.state === 'connecting') set('down', state.error || 'unreachable');
    client.options.reconnectPeriod = Math.min(LAST_RETRY_MS, (client.options.reconnectPeriod || FIRST_RETRY_MS) * 2);
  });
  onState(state);
  return { client, state: () => state };
}
