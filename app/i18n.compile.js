// `npm run typecheck` needs the compiled messages before svelte-check runs (the build compiles them itself).
import { compile } from '@inlang/paraglide-js';
import { i18nOptions } from './i18n.config.js';

await compile(i18nOptions);
