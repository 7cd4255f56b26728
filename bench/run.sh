#!/usr/bin/env bash
# npm run bench: every benchmark, one after the other (each starts and stops its own processes, loopback only).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/bootstrap.sh
source scripts/ros-env.sh
# npm run bench -- --soak [--minutes N --clients N --rate HZ]: the soak alone, then exit. It is not part of the
# default run below because it takes 10 minutes by default; run it when the machine is quiet.
if [[ "${1:-}" == "--soak" ]]; then
  shift
  echo "== soak: many clients through the BFF for minutes, RSS of the BFF and of rosbridge =="
  exec node bench/soak_bench.mjs "$@"
fi
echo "== rosbridge server (direct) =="
python bench/rosbridge_bench.py
echo; echo "== BFF relay path =="
node bench/bff_relay_bench.mjs
if [[ -f bench/sim_bench.py ]]; then echo; echo "== simulated cell =="; python bench/sim_bench.py; fi
echo; echo "== manual motion: hold-to-run jog through the page =="
node bench/manual_bench.mjs
echo; echo "== manual motion on a ros_control arm, the iiwa cell: hold-to-run jog through the page =="
BENCH_CELL=config/iiwa-cell.yaml node bench/manual_bench.mjs
echo; echo "== sensors page: six 100 Hz series on a phone, CPU throttled 4x =="
node bench/sensors_bench.mjs
echo; echo "== BFF back-pressure: slow link, stalled reader, fast clients beside a stalled one =="
node bench/bff_backpressure_bench.mjs
