// The video feature: a stream's type in the cell file (schema and cross-reference), what a role's UI gets, and the
// grants: a CompressedImage stream is read directly, a raw one only through the video node (its request service
// and JPEG outputs), never the raw topic itself.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { FEATURES } from '../../src/features/index.js';
import { validateCell, CellConfigError } from '../../src/core/config/cell.js';
import { configFor } from '../../src/core/access/pages.js';
import { grantsFor } from '../../src/core/access/grants.js';
import { decide as allowed } from '../../src/core/access/rules.js';

/** @param {any[]} streams */
function cellWith(streams) {
  return {
    cell: { id: 'video-test', name: 'Video test cell' },
    pages: [{ id: 'home', title: 'Home' }, { id: 'video', title: 'Cameras' }],
    roles: { operator: { pages: ['home', 'video'] }, guest: { pages: ['home'] } },
    operation_mode: { topic: '/cell/mode', type: 'cell_msgs/OperationMode', modes: ['idle'] },
    video: { streams },
  };
}

const JPEG = { name: 'Bench', topic: '/cam/bench/image/compressed' };
const RAW = { name: 'Arm', topic: '/cam/arm/image_raw', type: 'raw', sim_size: [1280, 720] };

test('the UI gets each stream with its type; compressed when the cell file says nothing', () => {
  const cell = validateCell(cellWith([JPEG, RAW]), 'c.yaml', FEATURES);
  const video = /** @type {any} */ (configFor(cell, FEATURES, 'operator').features).video;
  assert.deepEqual(video.streams, [{ ...JPEG, type: 'compressed' }, { name: 'Arm', topic: RAW.topic, type: 'raw' }]);
});

test('a raw stream is granted through the video node only; a JPEG stream directly; a role without the page neither', () => {
  const cell = validateCell(cellWith([JPEG, RAW]), 'c.yaml', FEATURES);
  const g = grantsFor(cell, FEATURES, 'operator');
  const ok = (/** @type {string} */ op, /** @type {string} */ target) => allowed(g, op, target).allow;
  assert.equal(ok('subscribe', JPEG.topic), true);
  assert.equal(ok('subscribe', RAW.topic), false);
  assert.equal(ok('call_service', '/cell/video/request'), true);
  assert.equal(ok('subscribe', '/cell/video/cam_arm_image_raw/w640_q70'), true);
  assert.equal(ok('subscribe', '/cell/video/status'), true);
  assert.equal(ok('publish', '/cell/video/cam_arm_image_raw/w640_q70'), false);
  const guest = grantsFor(cell, FEATURES, 'guest');
  assert.equal(allowed(guest, 'call_service', '/cell/video/request').allow, false);
  // without a raw stream there is nothing of the video node to grant
  const plain = grantsFor(validateCell(cellWith([JPEG]), 'c.yaml', FEATURES), FEATURES, 'operator');
  assert.equal(allowed(plain, 'call_service', '/cell/video/request').allow, false);
});

test('a wrong type or size, or a size on a compressed stream, is refused with the field named', () => {
  assert.throws(() => validateCell(cellWith([{ ...RAW, type: 'h264' }]), 'c.yaml', FEATURES), (e) => e instanceof CellConfigError && /video\/streams\/0\/type|video\.streams\[0\]\.type/.test(e.message));
  assert.throws(() => validateCell(cellWith([{ ...RAW, sim_size: [0, 720] }]), 'c.yaml', FEATURES), (e) => e instanceof CellConfigError && /sim_size/.test(e.message));
  assert.throws(() => validateCell(cellWith([{ ...JPEG, sim_size: [640, 480] }]), 'c.yaml', FEATURES), (e) => e instanceof CellConfigError && /video\.streams\[0\]\.sim_size: only a raw stream/.test(e.message));
});
