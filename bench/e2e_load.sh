#!/usr/bin/env bash
# npm run bench -- e2e-load: every spec that moves an arm (manual, manual-lease, routines, process on the demo cell;
# manual, routines, process on the twin and the iiwa cells) repeated E2E_REPEAT times (3; quick: 1), beside a CPU hog
# at normal priority on every core (Debian's stress-ng), in e2e/run.sh's two lanes: lane A the demo cell on the phone
# then the iiwa cell, lane B the twin cell on the tablet. The motion path claims the CPU first (cell_nodes/priority.py);
# CELL_PRIORITIES=0 runs it without (the comparison). Prints each run's result and time; exits 1 if any test failed.
set -uo pipefail
cd "$(dirname "$0")/../e2e"
source lib/lanes.sh
repeat=${E2E_REPEAT:-$([ "${BENCH_QUICK:-0}" = 1 ] && echo 1 || echo 3)}
hog_cpus=$(nproc)
stress-ng --cpu "$hog_cpus" --quiet &
hog=$!
trap 'kill $hog 2>/dev/null; wait $hog 2>/dev/null' EXIT
echo "hog: stress-ng --cpu $hog_cpus (pid $hog, nice $(ps -o ni= -p $hog | tr -d ' ')); priorities ${CELL_PRIORITIES:-1}; each spec x $repeat"
motion=(manual.spec.js routines.spec.js process.spec.js)
timed() {  # timed <name> <run args...>: one run, then its line for the summary
  local name=$1 t0=$SECONDS rc=0; shift
  run "$name" "$@" || rc=1
  echo "$name $((SECONDS - t0)) $rc" >> "$summary"
  return $rc
}
summary=$(mktemp)
lane_a() {
  timed load-demo E2E_PORT=18080 E2E_UR_HOST=127.0.0.9 -- --project=phone --repeat-each="$repeat" \
    "${motion[@]/#/tests/}" tests/manual-lease.spec.js
  timed load-iiwa -- -c playwright.iiwa.config.js --repeat-each="$repeat" "${motion[@]/#/iiwa/}"
}
lane_b() {
  timed load-twin -- -c playwright.twin.config.js --repeat-each="$repeat" "${motion[@]/#/twin/}"
}
t0=$SECONDS
lane_a & a=$!
lane_b & b=$!
wait $a; wait $b
echo
echo "== loaded e2e: $((SECONDS - t0)) s; load average at the end: $(cut -d' ' -f1-3 /proc/loadavg) =="
rc=0
while read -r name secs failed; do
  printf '  %-10s %5s s  %s\n' "$name" "$secs" "$([ "$failed" = 0 ] && echo passed || echo FAILED)"
  [ "$failed" = 0 ] || rc=1
done < "$summary"
rm -f "$summary"
exit $rc
