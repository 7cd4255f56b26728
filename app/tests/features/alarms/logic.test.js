import { describe, it, expect } from 'vitest';
import { alarmViews, bannerAlarm, statusView, severityView, rosTimeMs, activeCount } from '../../../src/lib/features/alarms/logic.js';
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
