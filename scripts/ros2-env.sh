# Source this: the environment every ROS 2 process of the stack runs in (the ROS 2 counterpart of ros-env.sh).
# Discovery stays on this machine: localhost-only, and a domain of the stack's own (ROS_DOMAIN_ID, default 0;
# stacks side by side set their own). A robot PC that discovers its arm over the robot network sets the range and
# domain in the cell file (ros.discovery), which the stack passes on here.
_ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
_PREFIX="$_ROOT/ros_backend/install-ros2"
export PATH="$_ROOT/.venv-ros2/bin:/usr/bin:$PATH"
export ROS_VERSION=2 ROS_DISTRO=jazzy
export AMENT_PREFIX_PATH="$_PREFIX:$_ROOT/.venv-ros2${AMENT_PREFIX_PATH:+:$AMENT_PREFIX_PATH}"
export LD_LIBRARY_PATH="$_PREFIX/lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
export PYTHONPATH="$_ROOT:$_PREFIX/lib/python3.11/site-packages:$_ROOT/ros_backend/src/cell_rosbridge/src:$_ROOT/ros_backend/src/cell_nodes/src:$_ROOT/ros_backend/src/rosapi/src"
export ROS_AUTOMATIC_DISCOVERY_RANGE="${ROS_AUTOMATIC_DISCOVERY_RANGE:-LOCALHOST}"
export ROS_DOMAIN_ID="${ROS_DOMAIN_ID:-0}"
unset ROS_MASTER_URI ROS_HOSTNAME ROS_PACKAGE_PATH ROS_ROOT
unset _ROOT _PREFIX
