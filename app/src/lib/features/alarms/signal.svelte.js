/**
 * The alarm signal on every page: one subscription to the alarm list and the safety status for the whole app
 * (the shell's, through the feature list's `shell` entry), read by the menu badge, the banner, the Alarms page
 * and Home. Both topics are latched: the values are current exactly while the link is up.
 */
import { m } from '$lib/paraglide/messages.js';
import { NAMES, alarmViews, activeCount, bannerAlarm } from './logic.js';

export class AlarmSignal {
  /** @type {import('./logic.js').AlarmView[]} */
  alarms = $state([]);
  /** cell_msgs/SafetyStatus, or null before the first one. @type {any} */
  status = $state(null);
  /** When the list / status last arrived (ms), null before. */
  listAt = $state(/** @type {number | null} */ (null));
  statusAt = $state(/** @type {number | null} */ (null));
  /** The link is up and the subscriptions delivered. */
  live = $state(false);
  /** Keys of the alarms the banner was dismissed for. @type {Set<string>} */
  dismissed = $state(new Set());

  /** @param {() => number} [now] */
  constructor(now = Date.now) {
    this.now = now;
  }

  get active() {
    return activeCount(this.alarms);
  }

  /** The menu badge: the count of active alarms, or null when none (or nothing known). */
  get badge() {
    const n = this.active;
    return this.live && n > 0 ? { count: n, label: m.alarms_n_active({ count: n }) } : null;
  }

  get banner() {
    return this.live ? bannerAlarm(this.alarms, this.dismissed) : null;
  }

  /** Hide the banner for the alarms active now; the next alarm shows it again. */
  dismiss() {
    const next = new Set(this.dismissed);
    for (const a of this.alarms) if (a.active) next.add(a.key);
    this.dismissed = next;
  }

  /** @param {any} msg cell_msgs/AlarmList */
  updateList(msg) {
    this.alarms = alarmViews(msg);
    this.listAt = this.now();
    this.live = true;
  }

  /** @param {any} msg cell_msgs/SafetyStatus */
  updateStatus(msg) {
    this.status = msg;
    this.statusAt = this.now();
    this.live = true;
  }

  /** The link dropped: the values stay (shown stale), the badge and banner go. */
  lost() {
    this.live = false;
  }

  /**
   * Subscribe both topics on the app's connection; returns the unsubscribe.
   * @param {{ subscribe: (t: string, type: string, cb: (m: any) => void) => () => void }} ros
   */
  follow(ros) {
    const a = ros.subscribe(NAMES.list.topic, NAMES.list.type, (m) => this.updateList(m));
    const b = ros.subscribe(NAMES.status.topic, NAMES.status.type, (m) => this.updateStatus(m));
    return () => {
      a();
      b();
      this.lost();
    };
  }
}

export const alarmSignal = new AlarmSignal();
