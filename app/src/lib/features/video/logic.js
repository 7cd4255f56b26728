/**
 * The video (Cameras) feature's plain logic: how fast frames are asked for, how the stream is chosen, and the
 * remembered choice. The camera itself (CBOR frames, rate, age, zoom) is ui/CameraView.svelte + ui/camera.js,
 * shared with the Manual page.
 */

export const FEATURE_ID = 'video';
/** rosbridge throttle for the shown stream: up to 30 frames a second (the newest frame only, queue_length 1). */
export const THROTTLE_MS = 33;
/** Segmented buttons for a few streams (one tap), a select for more. */
export const MAX_BUTTONS = 4;
const KEY = 'cell-ui.video.stream';

/** @param {number} n  how many streams */
export const chooserKind = (n) => (n <= MAX_BUTTONS ? 'buttons' : 'select');

/** The stream last shown on this device (a topic), '' when none or no storage. @param {Storage | null | undefined} storage */
export function loadChoice(storage) {
  try {
    return storage?.getItem(KEY) ?? '';
  } catch {
    return '';
  }
}

/** @param {Storage | null | undefined} storage @param {string} topic */
export function saveChoice(storage, topic) {
  try {
    if (topic) storage?.setItem(KEY, topic);
  } catch {
    /* storage is optional */
  }
}
