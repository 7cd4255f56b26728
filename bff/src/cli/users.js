#!/usr/bin/env node
// npm run users -- add <name> --role <role> --password-stdin | passwd <name> --password-stdin | remove <name> | list
import { readEnv } from '../core/config/env.js';
import { UserStore, UsersError } from '../core/auth/users.js';
import { loadCell, CellConfigError } from '../core/config/cell.js';
import { FEATURES } from '../features/index.js';

const USAGE = `usage: npm run users -- add <name> --role <role> --password-stdin
       npm run users -- passwd <name> --password-stdin
       npm run users -- remove <name>
       npm run users -- list
Honours USERS_FILE and DATA_DIR; roles come from the cell file (CELL_CONFIG).`;

async function readStdin() {
  if (process.stdin.isTTY) throw new UsersError('--password-stdin: pipe the password in, e.g. printf %s "$PW" | npm run users -- ...');
  const chunks = [];
  for await (const c of process.stdin) chunks.push(c);
  return Buffer.concat(chunks).toString('utf8').replace(/\r?\n$/, '');
}

async function main(argv) {
  const env = readEnv();
  const store = new UserStore(env.usersFile);
  const [cmd, name, ...rest] = argv;
  const flag = (f) => rest.includes(f);
  const opt = (f) => { const i = rest.indexOf(f); return i >= 0 ? rest[i + 1] : undefined; };
  switch (cmd) {
    case 'list':
      for (const u of store.list()) console.log(`${u.username}\t${u.role}`);
      return;
    case 'add': {
      const role = opt('--role');
      if (!name || !role || !flag('--password-stdin')) throw new UsersError(USAGE);
      const roles = Object.keys(loadCell(env.cellConfig, FEATURES).roles);
      if (!roles.includes(role)) throw new UsersError(`unknown role "${role}" (the cell file defines: ${roles.join(', ')})`);
      await store.add(name, role, await readStdin());
      console.log(`added ${name} (${role}) to ${env.usersFile}`);
      return;
    }
    case 'passwd':
      if (!name || !flag('--password-stdin')) throw new UsersError(USAGE);
      await store.passwd(name, await readStdin());
      console.log(`password of ${name} changed`);
      return;
    case 'remove':
      if (!name) throw new UsersError(USAGE);
      store.remove(name);
      console.log(`removed ${name}`);
      return;
    default:
      throw new UsersError(USAGE);
  }
}

main(process.argv.slice(2)).catch((e) => {
  console.error(e instanceof UsersError || e instanceof CellConfigError ? e.message : e.stack || String(e));
  process.exit(2);
});
