# Source this: the environment every ROS process of the stack runs in.
_ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
export PATH="$_ROOT/.venv/bin:/usr/bin:$PATH"  # venv first: node scripts' `env python3` must see rospy
export ROS_HOSTNAME="${ROS_HOSTNAME:-127.0.0.1}"
export ROS_MASTER_URI="${ROS_MASTER_URI:-http://127.0.0.1:11311}"
if [[ -f "$_ROOT/ros_backend/devel/setup.bash" ]]; then
  _MASTER="$ROS_MASTER_URI"; _HOST="$ROS_HOSTNAME"
  # catkin's setup scripts read unset variables: relax `set -u` while they run.
  case $- in *u*) _NOUNSET=1; set +u ;; *) _NOUNSET= ;; esac
  # shellcheck disable=SC1091
  source "$_ROOT/ros_backend/devel/setup.bash"
  [[ -n "$_NOUNSET" ]] && set -u
  export ROS_MASTER_URI="$_MASTER" ROS_HOSTNAME="$_HOST"
fi
export PYTHONPATH="$_ROOT:${PYTHONPATH:-}"
unset _ROOT _MASTER _HOST _NOUNSET
