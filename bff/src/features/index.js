// The feature list: the one place that says which features this BFF has, in menu order of a default cell.
// Adding a feature = its folder + one line here (docs/architecture.md).
import home from './home/index.js';
import modules from './modules/index.js';
import process from './process/index.js';
import manual from './manual/index.js';
import scene from './scene/index.js';
import sensors from './sensors/index.js';
import video from './video/index.js';
import parameters from './parameters/index.js';
import routines from './routines/index.js';
import alarms from './alarms/index.js';
import database from './database/index.js';
import system from './system/index.js';
import recorder from './recorder/index.js';
import inspect from './inspect/index.js';
import plant from './plant/index.js';

/** @type {import('../core/features/feature.js').Feature[]} */
export const FEATURES = [home, modules, process, manual, scene, sensors, video, parameters, routines, alarms, database, system, recorder, inspect, plant];
