#!/usr/bin/env bash
# npm run bench -- e2e-load: every spec that moves an arm (manual, manual-lease, routines, process on the demo cell;
# manual, routines, process on the twin and the iiwa cells) repeated E2E_REPEAT times (3; quick: 1), beside a CPU hog
# at normal priority on every core (Debian's stress-ng), in e2e/run.sh's two lanes: lane A the demo cell on the phone
# then the iiwa cell, lane B the twin cell on the tablet. The motion path claims the CPU first (cell_nodes/priority.py);
# CELL_PRIORITIES=0 runs it without (the comparison). Prints each run's result and time; exits 1 if any test failed.
set -uo pipefail
cd "$(dirname "$0")/../e2e"
quick=${BENCH_QUICK:-0}
repeat=${E2E_REPEAT:-3}
if [ "$quick" = 1 ]; then repeat=${E2E_REPEAT:-1}; fi
cpus=$(nproc)
stress-ng --cpu "$cpus" --quiet &
hog=$!
trap 'kill $hog 2>/dev/null; wait $hog 2>/dev/null' EXIT
echo "hog: stress-ng --cpu $cpus at nice $(ps -o ni= -p "$hog" | tr -d ' '), CELL_PRIORITIES=${CELL_PRIORITIES:-1}, each spec x $repeat"
summary=$(mktemp)

# timed <name> <env...> -- <playwright args...>: one run; its time and result go to the summary.
timed() {
  local name=$1 t0=$SECONDS rc=0
  bash lib/run-one.sh "$@" --repeat-each="$repeat" || rc=1
  echo "$name $((SECONDS-t0)) $rc" >> "$summary"
}

lane_a() {
  timed load-demo E2E_PORT=18080 E2E_UR_HOST=127.0.0.9 -- --project=phone \
    tests/manual.spec.js tests/manual-lease.spec.js tests/routines.spec.js tests/process.spec.js
  timed load-iiwa -- -c playwright.iiwa.config.js iiwa/manual.spec.js iiwa/routines.spec.js iiwa/process.spec.js
}

lane_b() {
  timed load-twin -- -c playwright.twin.config.js twin/manual.spec.js twin/routines.spec.js twin/process.spec.js
}

t0=$SECONDS
lane_a & a=$!
lane_b & b=$!
wait $a
wait $b
took=$((SECONDS-t0))
echo
echo "== loaded e2e: $took s, load average at the end: $(cut -d' ' -f1-3 /proc/loadavg) =="
rc=0
while read -r name secs failed; do
  if [ "$failed" = 0 ]; then result=passed; else result=FAILED; rc=1; fi
  printf '  %-10s %5s s  %s\n' "$name" "$secs" "$result"
done < "$summary"
rm -f "$summary"
exit $rc
