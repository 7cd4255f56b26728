#!/usr/bin/env bash
# npm run bench [-- [--quick] [NAME...]]: the benchmarks, one after the other (each starts and stops its own
# processes, loopback only). `npm run bench -- --help` lists the names.
#   (no name)   every benchmark but the soak: the full run, the reference for docs/performance.md (over 10 minutes)
#   NAME...     only these, in the order given
#   --quick     each in a short form (BENCH_QUICK=1: shorter durations, fewer runs, same figures): with no name the
#               same benchmarks as the full run, in under 5 minutes on 2 cores; combinable with NAMEs (--quick soak)
#   soak [--minutes N --clients N --rate HZ --json FILE]   (or --soak ...): the soak; options after it are its own
set -euo pipefail
cd "$(dirname "$0")/.."

read -r -a NAMES <<< 'rosbridge relay sim manual manual-iiwa sensors scene login backpressure video image-relay recorder logstorm e2e-load soak'
declare -A WHAT=(
  [rosbridge]='rosbridge server (direct)'
  [relay]='BFF relay path'
  [sim]='simulated cell'
  [manual]='manual motion: hold-to-run jog through the page'
  [manual-iiwa]='manual motion on a ros_control arm, the iiwa cell: hold-to-run jog through the page'
  [sensors]='sensors page: six 100 Hz series on a phone, CPU throttled 4x'
  [scene]='3D view while the arm moves: desktop, and a phone with the CPU throttled 4x'
  [login]='login form usable on a mid-range phone (4x CPU, 1.6 Mbit/s, 150 ms RTT), cold and from the service worker; its JavaScript bytes; English and Spanish'
  [backpressure]='BFF back-pressure: slow link, 80 ms link, stalled reader, fast clients beside a stalled one'
  [video]='raw 720p camera at 30 Hz to 5 phone viewers through the video node and the BFF, against full-size JPEG to each'
  [image-relay]='relay CPU per image frame: a 30 Hz x 30 KB JPEG to 5 viewers, rosbridge_suite direct vs ours direct vs the BFF path (reference: bench/reference/rosbridge_suite.sh setup)'
  [recorder]='flight recorder: CPU and RSS of the recorder node with the demo cell running its process, a save'
  [logstorm]='ROS log storm (1 kHz for 60 s) with the Inspect page open on a tablet: RSS of the BFF, inspect node, rosout, rosbridge; page fps and a filter click'
  [e2e-load]='every e2e spec that moves an arm, 3 times, on the three cells, beside a CPU hog on every core (stress-ng)'
  [soak]='25 clients through the BFF beside the simulated cell (camera viewer, jog session, running process) for minutes: RSS of every process, log errors, liveness'
)
declare -A FULL=(
  [rosbridge]='7 scenarios x 5 s' [relay]='3 x 5 s' [sim]='15 s' [manual]='5 runs each' [manual-iiwa]='5 runs each'
  [sensors]='3 x 10 s' [scene]='4 x 8 s' [login]='5 runs per language' [backpressure]='slow 60 s, rtt 30 s, stall 300 s, fast 4 x 20 s' [video]='2 x 20 s' [image-relay]='3 rounds x 3 x 15 s' [recorder]='150 s' [logstorm]='60 s' [e2e-load]='3 repeats (by name only)' [soak]='10 x 1 min (by name only)'
)
declare -A QUICK=(
  [rosbridge]='7 x 1.5 s' [relay]='3 x 1.5 s' [sim]='4 s' [manual]='3 runs each' [manual-iiwa]='3 runs each'
  [sensors]='3 x 3 s' [scene]='4 x 3 s' [login]='2 runs per language' [backpressure]='slow 10 s, rtt 10 s, stall 10 s, fast 2 x 2 s' [video]='2 x 5 s' [image-relay]='3 x 5 s' [recorder]='25 s' [logstorm]='15 s' [e2e-load]='1 repeat' [soak]='3 "minutes" of 8 s'
)

usage() {
  printf '%s\n' \
    'Usage: npm run bench -- [--quick] [NAME...] [soak options]' \
    '  (no name)  every benchmark but the soak, full length (over 10 minutes; the figures of docs/performance.md)' \
    '  --quick    each benchmark in a short form, same figures (with no name: those of the full run, < 5 min)' \
    '  NAME...    only these benchmarks' \
    '  soak options (after soak or --soak): --minutes N --clients N --rate HZ --json FILE' \
    'Benchmarks:'
  for n in "${NAMES[@]}"; do printf '  %-13s %s\n  %-13s full: %s; quick: %s\n' "$n" "${WHAT[$n]}" '' "${FULL[$n]}" "${QUICK[$n]}"; done
}

known() { local n; for n in "${NAMES[@]}"; do [[ "$n" == "$1" ]] && return 0; done; return 1; }
quick=0
selected=()
soak_args=()
in_soak=0
for a in "$@"; do
  case "$a" in
    -h|--help) usage; exit 0 ;;
    --quick) quick=1 ;;
    --soak) selected+=(soak); in_soak=1 ;;
    *)
      if ((in_soak)); then soak_args+=("$a"); continue; fi
      if known "$a"; then
        selected+=("$a")
        if [[ "$a" == soak ]]; then in_soak=1; fi
      else
        echo "bench: unknown benchmark or option: $a" >&2
        usage >&2
        exit 1
      fi ;;
  esac
done
if ((${#selected[@]} == 0)); then selected=("${NAMES[@]:0:${#NAMES[@]}-2}"); fi  # all but e2e-load and the soak
if ((quick)); then export BENCH_QUICK=1; else unset BENCH_QUICK; fi  # the full run is never shortened

bash scripts/bootstrap.sh
source scripts/ros-env.sh

run_one() {
  case "$1" in
    rosbridge) python bench/rosbridge_bench.py && (source scripts/ros2-env.sh && python bench/rosbridge_bench.py) ;;
    relay) node bench/bff_relay_bench.mjs ;;
    sim) python bench/sim_bench.py ;;
    manual) node bench/manual_bench.mjs ;;
    manual-iiwa) BENCH_CELL=config/iiwa-cell.yaml node bench/manual_bench.mjs ;;
    sensors) node bench/sensors_bench.mjs ;;
    scene) node bench/scene_bench.mjs ;;
    login) node bench/login_bench.mjs ;;
    backpressure) node bench/bff_backpressure_bench.mjs ;;
    video) node bench/video_bench.mjs ;;
    image-relay) node bench/image_relay_bench.mjs ;;
    recorder) python bench/recorder_bench.py ;;
    logstorm) node bench/logstorm_bench.mjs ;;
    e2e-load) bash bench/e2e_load.sh ;;
    soak) node bench/soak_bench.mjs ${soak_args[@]+"${soak_args[@]}"} ;;
  esac
}

interrupted=0
trap 'interrupted=1' INT
failed=()
summary=()
t_all=$EPOCHREALTIME
tag=''; if ((quick)); then tag=' (quick)'; fi
first=1
for n in "${selected[@]}"; do
  if ((!first)); then echo; fi
  first=0
  echo "== $n: ${WHAT[$n]}$tag =="
  t0=$EPOCHREALTIME
  rc=0
  run_one "$n" || rc=$?
  secs=$(awk -v a="$t0" -v b="$EPOCHREALTIME" 'BEGIN { printf "%.0f", b - a }')
  if ((rc)); then failed+=("$n"); summary+=("$(printf '  %-13s %5s s  FAILED (exit %s)' "$n" "$secs" "$rc")")
  else summary+=("$(printf '  %-13s %5s s' "$n" "$secs")"); fi
  if ((interrupted)); then break; fi
done
if ((${#selected[@]})); then
  echo
  echo "== bench${tag}: $(awk -v a="$t_all" -v b="$EPOCHREALTIME" 'BEGIN { printf "%.0f", b - a }') s in all, bootstrap not counted =="
  printf '%s\n' "${summary[@]}"
fi
if ((interrupted)); then exit 130; fi
if ((${#failed[@]})); then echo "failed: ${failed[*]}" >&2; exit 1; fi
