#!/usr/bin/env bash
# The whole e2e suite (`npm test -w e2e`): every spec of each cell on the phone, tablet and desktop profiles. The demo
# cell runs in two lanes at once, each against a stack of its own (own ports, own controller address, own output
# directory): the phone and the tablet (ports 18080-18086, UR controller at 127.0.0.9), and the desktop (18380-18386,
# 127.0.0.19). Much of a spec's time is the cell's own real-time waits (a lease timeout, a stale diagnostic, a
# recording's after-time), so two lanes on two cores take much less than one after the other. The twin-arm cell
# (18180-) and the iiwa cell (18280-) then run alone: beside a demo lane, the host's load (about 20) once kept a twin
# arm's controller from answering its driver within the driver's 1 s watchdog. A run goes on after a failing one, so
# one run tells every failure; the exit status is non-zero if any failed. Lines are prefixed with their run.
set -uo pipefail
cd "$(dirname "$0")"

# run <name> <env...> -- <playwright args...>: one Playwright run, its output prefixed, its status returned.
run() {
  local name=$1; shift
  local -a env=()
  while [ "$1" != "--" ]; do env+=("$1"); shift; done
  shift
  env "${env[@]}" E2E_OUTPUT_DIR="test-results/$name" npx playwright test "$@" 2>&1 | sed -u "s/^/[$name] /"
  return "${PIPESTATUS[0]}"
}

lane_a() {
  run demo-phone-tablet E2E_PORT=18080 E2E_UR_HOST=127.0.0.9 -- --project=phone --project=tablet
}

lane_b() {
  run demo-desktop E2E_PORT=18380 E2E_UR_HOST=127.0.0.19 -- --project=desktop
}

t0=$(date +%s)
lane_a & a=$!
lane_b & b=$!
rc=0
wait $a || rc=1
wait $b || rc=1
run twin -- -c playwright.twin.config.js || rc=1
run iiwa -- -c playwright.iiwa.config.js || rc=1
echo "e2e: done in $(( $(date +%s) - t0 )) s ($([ $rc = 0 ] && echo 'all passed' || echo 'FAILED'))"
exit $rc
