import { describe, it, expect } from 'vitest';
import { alarmViews, bannerAlarm, statusView, severityView, rosTimeMs, activeCount, alarmText, statusText } from '../../../src/lib/features/alarms/logic.js';
import { setLocale } from '../../../src/lib/paraglide/runtime.js';
import { AlarmSignal } from '../../../src/lib/features/alarms/signal.svelte.js';

const t = (/** @type {number} */ s) => ({ secs: s, nsecs: 0 });
const list = {
  alarms: [
    { id: 'force.limit', text: 'Force above 80 N', severity: 1, active: false, since: t(100), last_seen: t(120), source: 'force', count: 1 },
    { id: 'device.gripper_fault', text: 'Gripper fault', severity: 2, active: true, since: t(200), last_seen: t(210), source: 'device', count: 1 },
    { id: 'robot.arm.reduced_mode', text: 'Robot arm: reduced mode', severity: 1, active: true, since: t(300), last_seen: t(310), source: 'robot', count: 2 },
  ],
};

describe('alarm list', () => {
  it('puts active first, then the most severe, then the newest', () => {
    expect(alarmViews(list).map((a) => a.id)).toEqual(['device.gripper_fault', 'robot.arm.reduced_mode', 'force.limit']);
  });
  it('converts ROS times and leaves unset ones empty', () => {
    expect(rosTimeMs(t(2))).toBe(2000);
    expect(rosTimeMs({ secs: 0, nsecs: 0 })).toBeNull();
    expect(alarmViews(list)[0]).toMatchObject({ since: 200000, lastSeen: 210000, source: 'device' });
  });
  it('ignores malformed entries and counts the active ones', () => {
    expect(alarmViews({ alarms: [null, { text: 'no id' }, ...list.alarms] })).toHaveLength(3);
    expect(activeCount(alarmViews(list))).toBe(2);
    expect(alarmViews(undefined)).toEqual([]);
  });
  it('gives severity and status a label and a tone', () => {
    expect(severityView(2)).toEqual({ tone: 'danger', label: 'Error' });
    expect(severityView(9).label).toBe('Error');
    expect(statusView({ status: 'normal' })).toEqual({ tone: 'ok', label: 'Normal' });
    expect(statusView({ status: 'protective stop' })).toEqual({ tone: 'danger', label: 'Protective stop' });
    expect(statusView(null).label).toBe('Unknown');
  });
});

describe('banner and badge', () => {
  it('shows the newest active alarm until dismissed, and comes back for the next one', () => {
    const sig = new AlarmSignal(() => 1);
    expect(sig.banner).toBeNull();
    sig.updateList(list);
    expect(sig.badge).toEqual({ count: 2, label: '2 active alarms' });
    expect(sig.banner?.id).toBe('robot.arm.reduced_mode');
    sig.dismiss();
    expect(sig.banner).toBeNull();
    // A new alarm comes in: the banner is back, for it.
    sig.updateList({ alarms: [...list.alarms, { id: 'module.Vision', text: 'Vision incomplete', severity: 1, active: true, since: t(400), count: 1 }] });
    expect(sig.banner?.id).toBe('module.Vision');
    sig.dismiss();
    // The same alarm becoming active again (count 2) is news too.
    sig.updateList({ alarms: [{ id: 'module.Vision', text: 'Vision incomplete', severity: 1, active: true, since: t(400), count: 2 }] });
    expect(sig.banner?.id).toBe('module.Vision');
  });
  it('shows no badge or banner while the link is down', () => {
    const sig = new AlarmSignal(() => 1);
    sig.updateList(list);
    sig.lost();
    expect(sig.badge).toBeNull();
    expect(sig.banner).toBeNull();
    expect(sig.alarms).toHaveLength(3);
  });
});


describe("an alarm's words in the user's language", () => {
  const force = alarmViews({ alarms: [{ id: 'force.limit', text: 'wrist force 1250 N above the 80.5 N limit (/cell/wrench)', code: 'force.limit',
    params: [{ key: 'force', value: '1250' }, { key: 'limit', value: '80.5' }, { key: 'topic', value: '/cell/wrench' }], severity: 2, active: true, since: t(1), count: 1 }] })[0];
  const device = { id: 'device.gripper_fault', text: 'Gripper fault: no answer', code: '', params: {} };
  const texts = { 'device.gripper_fault': { en: 'Gripper fault', es: 'Fallo de la pinza' } };
  it('says a coded alarm from the catalogue with its parameters (numbers in the locale), the cell file\'s by id first, else the robot PC\'s text', () => {
    expect(force.code).toBe('force.limit');
    expect(force.params).toEqual({ force: '1250', limit: '80.5', topic: '/cell/wrench' });
    expect(alarmText(force)).toBe('wrist force 1,250 N above the 80.5 N limit (/cell/wrench)');
    expect(alarmText(device)).toBe('Gripper fault: no answer');
    expect(alarmText(device, texts)).toBe('Gripper fault');
    // An unknown code (a newer node than this app): the node's own text.
    expect(alarmText({ ...force, code: 'force.something_new' })).toBe(force.text);
    setLocale('es', { reload: false });
    try {
      expect(alarmText(force)).toBe('fuerza en la muñeca de 1250 N, por encima del límite de 80,5 N (/cell/wrench)');
      expect(alarmText(device, texts)).toBe('Fallo de la pinza');
      expect(alarmText(device)).toBe('Gripper fault: no answer');
      const status = { text: 'Robot arm: protective stop: …', code: 'robot.safety.protective_stop', params: [{ key: 'group', value: 'arm' }], alarm_id: 'robot.arm.protective_stop' };
      expect(statusText(status)).toBe('Robot arm: parada de protección: el robot se ha detenido; elimine la causa y desbloquéelo');
      expect(statusText({ text: 'no active alarm', code: '' })).toBe('ninguna alarma activa');
      expect(statusText({ text: 'Gripper fault: no answer', code: '', alarm_id: 'device.gripper_fault' }, texts)).toBe('Fallo de la pinza');
    } finally {
      setLocale('en', { reload: false });
    }
  });
});
