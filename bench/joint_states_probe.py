"""A ros_control arm's own view of itself, for bench/manual_bench.mjs on a ros_control cell: its driver's joint
states (the simulated iiwa driver publishes them at 200 Hz) and the TCP speed from its URDF (the same kinematics the
robot driver uses). Prints one line per joint state: wall time (s), TCP linear speed (m/s), largest joint speed
(rad/s). Usage: python bench/joint_states_probe.py CELL_FILE [GROUP]
"""
from __future__ import annotations

import sys
import time

import rospy
import yaml
from sensor_msgs.msg import JointState

from cell_nodes.manual.config import parse_manual
from cell_nodes.manual.ros_control.kinematics import Kinematics


def main(cell_file: str, group: str = "") -> None:
    with open(cell_file, encoding="utf-8") as f:
        config = parse_manual(yaml.safe_load(f).get("manual"))
    g = config.groups[group] if group else next(iter(config.groups.values()))
    spec = g.ros_control
    if spec is None:
        raise SystemExit(f"group {g.name} is no ros_control group")
    rospy.init_node("bench_joint_states_probe", anonymous=True, disable_signals=True)
    deadline = time.monotonic() + 30
    while not rospy.has_param(spec.robot_description or "/robot_description"):
        if time.monotonic() > deadline:
            raise SystemExit("no robot_description")
        time.sleep(0.1)
    urdf = rospy.get_param(spec.robot_description or "/robot_description")
    kin = Kinematics.from_urdf(urdf, spec.base_link, spec.tip_link)

    def on_joints(msg: JointState) -> None:
        index = {n: i for i, n in enumerate(msg.name)}
        if any(j not in index for j in kin.joint_names) or len(msg.velocity) != len(msg.name):
            return
        q = [msg.position[index[j]] for j in kin.joint_names]
        qd = [msg.velocity[index[j]] for j in kin.joint_names]
        sys.stdout.write(f"{time.time():.6f} {kin.tcp_speed(q, qd):.6f} {max(abs(v) for v in qd):.6f}\n")
        sys.stdout.flush()

    rospy.Subscriber(spec.joint_states, JointState, on_joints, queue_size=50, tcp_nodelay=True)
    rospy.spin()


if __name__ == "__main__":
    main(*sys.argv[1:3])
