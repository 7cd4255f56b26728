/**
 * The app's feature list: the one place that says which features (pages) this build has.
 * Routing (the catch-all route), the menu and the menu icons all come from here.
 *
 * A feature is a folder `features/<id>/` (Page.svelte, its parts, plain-JS logic, its icon) plus one
 * entry below. Its id is the page id of the cell file, the /api/config `features` key and the ROS
 * namespace /cell/<id>/. The server decides which features a role sees (GET /api/config -> pages) and
 * the cell file's title wins over `title` here.
 */
import homeIcon from './home/icon.js';
import modulesIcon from './modules/icon.js';
import manualIcon from './manual/icon.js';
import sceneIcon from './scene/icon.js';
import sensorsIcon from './sensors/icon.js';
import videoIcon from './video/icon.js';
import processIcon from './process/icon.js';
import routinesIcon from './routines/icon.js';
import parametersIcon from './parameters/icon.js';
import alarmsIcon from './alarms/icon.js';
import databaseIcon from './database/icon.js';
import recorderIcon from './recorder/icon.js';
import inspectIcon from './inspect/icon.js';
import plantIcon from './plant/icon.js';
import systemIcon from './system/icon.js';
import { alarmSignal } from './alarms/signal.svelte.js';
import { m } from '$lib/paraglide/messages.js';

/**
 * A default page title in the user's language, and in English: a cell file that leaves a title at the English
 * default gets the translation (routing.js, cellTitle).
 * @param {(inputs?: {}, options?: { locale?: 'en' }) => string} msg
 */
const titled = (msg) => ({ title: msg(), title_en: msg({}, { locale: 'en' }) });

/** SVG path data (24x24, stroked) or a small component taking `size`. @typedef {string | import('svelte').Component<{ size?: number }>} IconSpec */

/**
 * What the shell passes to a feature's page.
 * @typedef {object} PageProps
 * @property {FeatureEntry} feature  this entry, with the cell file's title
 * @property {any} [section]  this feature's part of the cell file (/api/config `features[id]`), if any
 */

/**
 * @typedef {object} FeatureEntry
 * @property {string} id
 * @property {string} path  the URL path ('/' for home)
 * @property {string} title  default title, in the user's language (the cell file's wins)
 * @property {string} [title_en]  the default title in English
 * @property {IconSpec} icon
 * @property {() => Promise<{ default: import('svelte').Component<any> }>} load  lazy page import
 * @property {() => Promise<{ default: import('svelte').Component<{ path: string }> }>} [shell]  a part the shell
 *   draws on every page for roles that see this feature (e.g. the alarm banner); gets the feature's path
 * @property {() => ({ count: number, label: string } | null)} [badge]  a live count beside the menu entry
 */

/** @type {FeatureEntry[]} */
export const features = [
  { id: 'home', path: '/', ...titled(m.nav_page_home), icon: homeIcon, load: () => import('./home/Page.svelte') },
  { id: 'modules', path: '/modules', ...titled(m.nav_page_modules), icon: modulesIcon, load: () => import('./modules/Page.svelte') },
  { id: 'process', path: '/process', ...titled(m.nav_page_process), icon: processIcon, load: () => import('./process/Page.svelte') },
  { id: 'manual', path: '/manual', ...titled(m.nav_page_manual), icon: manualIcon, load: () => import('./manual/Page.svelte') },
  { id: 'scene', path: '/scene', ...titled(m.nav_page_scene), icon: sceneIcon, load: () => import('./scene/Page.svelte') },
  { id: 'sensors', path: '/sensors', ...titled(m.nav_page_sensors), icon: sensorsIcon, load: () => import('./sensors/Page.svelte') },
  { id: 'video', path: '/video', ...titled(m.nav_page_video), icon: videoIcon, load: () => import('./video/Page.svelte') },
  { id: 'parameters', path: '/parameters', ...titled(m.nav_page_parameters), icon: parametersIcon, load: () => import('./parameters/Page.svelte') },
  { id: 'routines', path: '/routines', ...titled(m.nav_page_routines), icon: routinesIcon, load: () => import('./routines/Page.svelte') },
  {
    id: 'alarms', path: '/alarms', ...titled(m.nav_page_alarms), icon: alarmsIcon, load: () => import('./alarms/Page.svelte'),
    shell: () => import('./alarms/Shell.svelte'), badge: () => alarmSignal.badge,
  },
  { id: 'recorder', path: '/recorder', ...titled(m.nav_page_recorder), icon: recorderIcon, load: () => import('./recorder/Page.svelte') },
  { id: 'inspect', path: '/inspect', ...titled(m.nav_page_inspect), icon: inspectIcon, load: () => import('./inspect/Page.svelte') },
  { id: 'plant', path: '/plant', ...titled(m.nav_page_plant), icon: plantIcon, load: () => import('./plant/Page.svelte') },
  { id: 'database', path: '/database', ...titled(m.nav_page_database), icon: databaseIcon, load: () => import('./database/Page.svelte') },
  { id: 'system', path: '/system', ...titled(m.nav_page_system), icon: systemIcon, load: () => import('./system/Page.svelte') },
];
