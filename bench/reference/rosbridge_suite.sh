#!/usr/bin/env bash
# The reference server for the image relay bench: rosbridge_suite 0.11.17 (the ROS 1 branch, Python), run from its
# source beside our stack (Debian has no package of it). Bench-only: nothing in the product or its tests uses it.
#   rosbridge_suite.sh setup         fetch and build it into $RBS_DIR (default ~/.cache/cell-bench/rosbridge_suite)
#   rosbridge_suite.sh run PORT      run its websocket server on 127.0.0.1:PORT (ROS_MASTER_URI from the caller)
# Source: $RBS_GIT (a clone or bare mirror of RobotWebTools/rosbridge_suite) or else github.com; branch ros1.
set -euo pipefail
ROOT="$(cd "$(dirname "$0")/../.." && pwd)"
RBS_DIR="${RBS_DIR:-$HOME/.cache/cell-bench/rosbridge_suite}"
RBS_GIT="${RBS_GIT:-https://github.com/RobotWebTools/rosbridge_suite.git}"
REV=55a6bdb   # 0.11.17

setup() {
  [[ -f "$RBS_DIR/ready" ]] && return 0
  rm -rf "$RBS_DIR" && mkdir -p "$RBS_DIR"
  if [[ -d "$RBS_GIT" ]]; then git -C "$RBS_GIT" archive "$REV" | tar -x -C "$RBS_DIR"
  else git clone -q --branch ros1 "$RBS_GIT" "$RBS_DIR/clone" && git -C "$RBS_DIR/clone" archive "$REV" | tar -x -C "$RBS_DIR"; fi
  # shellcheck disable=SC1091
  source "$ROOT/scripts/ros-env.sh"
  pip install -q --target "$RBS_DIR/pylib" 'autobahn<24' twisted pymongo tornado
  # its messages, and rosauth's one service (imported even with authentication off): bench/reference/rosauth
  mkdir -p "$RBS_DIR/ws/src"
  cp -r "$RBS_DIR/rosbridge_msgs" "$ROOT/bench/reference/rosauth" "$RBS_DIR/ws/src/"
  (cd "$RBS_DIR/ws" && catkin_make -DPYTHON_EXECUTABLE=/usr/bin/python3 -DCATKIN_ENABLE_TESTING=OFF >"$RBS_DIR/catkin.log" 2>&1) \
    || { tail -20 "$RBS_DIR/catkin.log" >&2; exit 1; }
  touch "$RBS_DIR/ready"
}

case "${1:-}" in
  setup) setup ;;
  run)
    [[ -f "$RBS_DIR/ready" ]] || { echo "rosbridge_suite is not set up: $0 setup" >&2; exit 3; }
    master="${ROS_MASTER_URI:-}"
    # shellcheck disable=SC1091
    source "$ROOT/scripts/ros-env.sh"
    # shellcheck disable=SC1091
    source "$RBS_DIR/ws/devel/setup.bash" --extend
    export ROS_MASTER_URI="${master:-$ROS_MASTER_URI}"
    export PYTHONPATH="$RBS_DIR/rosbridge_library/src:$RBS_DIR/rosbridge_server/src:$RBS_DIR/pylib:$PYTHONPATH"
    exec python "$RBS_DIR/rosbridge_server/scripts/rosbridge_websocket.py" "_port:=${2:?port}" _address:=127.0.0.1 __name:=rosbridge_reference ;;
  *) sed -n 2,6p "$0" >&2; exit 2 ;;
esac
