import fs from 'node:fs';
import { stopStack } from './stack.js';
import { STATE_FILE } from './global-setup.js';

export default async function globalTeardown() {
  const stack = globalThis.__cellStack;
  if (stack) await stopStack(stack.proc);
  fs.rmSync(STATE_FILE, { force: true });
}
