#!/usr/bin/env bash
# Every suite, in order of speed: the type check, BFF unit, app unit, Python (unit + integration on live roscores;
# the ROS 2 suites under .venv-ros2 after them),
# the supervisor, then Playwright end to end against the whole stack. Stops at the first failing suite.
set -euo pipefail
cd "$(dirname "$0")/.."
export PLAYWRIGHT_SKIP_BROWSER_DOWNLOAD=1
t0=$(date +%s)
step() { printf '\n=== %s ===\n' "$*"; }

step "types (checkJs: tsc for bff, svelte-check for app)"
npm run typecheck -w bff --silent
npm run typecheck -w app --silent

step "bff (node:test)"
npm test -w bff --silent

step "app (vitest)"
npm test -w app --silent

step "ros_backend + sim (pytest, live roscore)"
( source scripts/ros-env.sh && python -m pytest -q )

step "ROS 2 Jazzy: our interfaces, and the rosbridge protocol on rclpy, same test bodies as on ROS 1"
( source scripts/ros2-env.sh && python -m pytest -q ros_backend/ros2/test/test_interfaces.py \
    ros_backend/src/cell_rosbridge/test/test_generations.py ros_backend/src/cell_rosbridge/test/test_actions_ros2.py \
    ros_backend/src/cell_nodes/test/test_operation_mode.py ros_backend/src/cell_nodes/test/test_parameters_node.py \
    ros_backend/src/cell_nodes/test/test_monitor_nodes.py ros_backend/src/cell_nodes/test/test_alarms_node.py \
    ros_backend/src/cell_nodes/test/test_alarms_twin_node.py ros_backend/src/cell_nodes/test/test_video_node.py \
    ros_backend/ros2/test/test_discovery.py )

step "stack supervisor (node:test)"
node --test --test-concurrency=1 scripts/test/*.test.js

step "e2e (Playwright: phone, tablet, desktop)"
npm test -w e2e --silent

printf '\nall suites passed in %s s\n' "$(( $(date +%s) - t0 ))"
