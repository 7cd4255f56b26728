// The BFF process: HTTP server + /ros upgrade. Exits non-zero with a clear message on a bad cell file.
import http from 'node:http';
import { readEnv } from './config/env.js';
import { createBff, StartupError } from './app.js';
import { CellConfigError } from './config/cell.js';

const env = readEnv();
let bff;
try {
  bff = await createBff(env);
} catch (e) {
  if (e instanceof CellConfigError || e instanceof StartupError) {
    console.error(e.message);
    process.exit(2);
  }
  throw e;
}
if (bff.initial) {
  console.log(`[bff] first start: created users ${bff.initial.users.map((u) => `${u.username}/${u.password}`).join(', ')}`);
  console.log(`[bff] (also written once to ${bff.initial.file}, mode 0600)`);
}
const server = http.createServer(bff.app);
server.on('upgrade', (req, socket, head) => {
  const { pathname } = new URL(req.url, 'http://x');
  if (pathname === '/ros') bff.relay.handleUpgrade(req, socket, head);
  else socket.end('HTTP/1.1 404 Not Found\r\nConnection: close\r\n\r\n');
});
server.listen(env.port, env.host, () => console.log(`[bff] listening on http://${env.host}:${env.port}`));

function shutdown() {
  bff.close();
  server.close(() => process.exit(0));
  server.closeAllConnections();
  setTimeout(() => process.exit(0), 1500).unref();
}
process.on('SIGINT', shutdown);
process.on('SIGTERM', shutdown);
