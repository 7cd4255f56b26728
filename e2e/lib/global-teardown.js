import { stopStack } from './stack.js';

export default async function globalTeardown() {
  const stack = globalThis.__cellStack;
  if (stack) await stopStack(stack.proc);
}
