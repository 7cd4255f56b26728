#!/usr/bin/env bash
# The whole e2e suite (`npm test -w e2e`): the layout, touch and accessibility specs on the phone, the tablet and the
# desktop, every behaviour once, on the profile of the user it is for (playwright.config.js). Two lanes run at once,
# each against stacks of its own (own ports, own controller addresses, own output directory):
#   lane A: the demo cell on the phone (18080-18086, UR controller at 127.0.0.9), then the iiwa cell (18280-);
#   lane B: the demo cell on the desktop and the tablet (18380-18386, 127.0.0.19), then the twin-arm cell (18180-).
# Much of a spec's time is the cell's own real-time waits (a lease timeout, a stale diagnostic, a recording's
# after-time), so two lanes on two cores take much less than one after the other. The twin and iiwa cells run beside
# the other lane again: the motion path (the drivers, the simulated controllers) claims the CPU first
# (cell_nodes/priority.py), so a loaded host no longer starves a controller past its driver's watchdog. A run goes
# on after a failing one, so one run tells every failure; the exit status is non-zero if any failed. Lines are
# prefixed with their run.
set -uo pipefail
cd "$(dirname "$0")"

lane_a() {
  local rc=0
  bash lib/run-one.sh demo-phone E2E_PORT=18080 E2E_UR_HOST=127.0.0.9 -- --project=phone || rc=1
  bash lib/run-one.sh iiwa -- -c playwright.iiwa.config.js || rc=1
  return $rc
}

lane_b() {
  local rc=0
  bash lib/run-one.sh demo-desktop-tablet E2E_PORT=18380 E2E_UR_HOST=127.0.0.19 -- --project=desktop --project=tablet || rc=1
  bash lib/run-one.sh twin -- -c playwright.twin.config.js || rc=1
  return $rc
}

t0=$(date +%s)
lane_a & a=$!
lane_b & b=$!
rc=0
wait $a || rc=1
wait $b || rc=1
echo "e2e: done in $(( $(date +%s) - t0 )) s ($([ $rc = 0 ] && echo 'all passed' || echo 'FAILED'))"
exit $rc
