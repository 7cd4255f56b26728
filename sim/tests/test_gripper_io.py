"""Digital output 0 drives the gripper: it closes on a cube, the tactile pad and the wrist wrench respond."""
from __future__ import annotations

import math
import threading
from pathlib import Path

import numpy as np
import pytest
import rospy
import rtde_control
import rtde_io
import rtde_receive
from cell_msgs.msg import Scatter
from geometry_msgs.msg import WrenchStamped

from conftest import wait_for
from sim import kinematics as kin
from sim.world import CUBE_SIZE, World

HOST = "127.0.0.13"
SEED = 7
# A test cell, not config/demo-cell.yaml: the sensor topics are whatever the cell file names.
CELL = Path(__file__).resolve().parent / "cells" / "renamed-topics.yaml"
TACTILE_TOPIC = "/robot2/finger/tactile"
WRENCH_TOPIC = "/robot2/ft_sensor/wrench"


class Latest:
    """Keeps the newest message of a topic."""

    def __init__(self, topic: str, mtype) -> None:
        self.msg = None
        self.count = 0
        self._lock = threading.Lock()
        self.sub = rospy.Subscriber(topic, mtype, self._cb, queue_size=5)

    def _cb(self, msg) -> None:
        with self._lock:
            self.msg = msg
            self.count += 1

    def fresh(self, timeout: float = 3.0):
        start = self.count
        wait_for(lambda: self.count > start + 1, timeout, what=f"fresh {self.sub.name}")
        return self.msg


def grasp_pose(cube_pos, cube_orn, home_rotvec, z: float) -> np.ndarray:
    """TCP pose above/at a cube with the fingers closing across two opposite faces (closest to world x)."""
    r_home = kin.rotvec_to_matrix(home_rotvec)
    yaw = math.atan2(2 * (cube_orn[3] * cube_orn[2] + cube_orn[0] * cube_orn[1]),
                     1 - 2 * (cube_orn[1] ** 2 + cube_orn[2] ** 2))
    finger_dir = math.atan2(r_home[1, 1], r_home[0, 1])  # tool y (finger motion) in the world xy plane
    want = min((yaw + k * math.pi / 2 for k in range(-4, 5)), key=lambda a: abs(math.sin(a)) + abs(a - finger_dir) * 1e-3)
    turn = math.atan2(math.sin(want - finger_dir), math.cos(want - finger_dir))
    turn = (turn + math.pi / 2) % math.pi - math.pi / 2  # fingers are symmetric: at most +-90 degrees
    rot = kin.rotvec_to_matrix([0, 0, turn]) @ r_home
    return np.concatenate([[cube_pos[0], cube_pos[1], z], kin.matrix_to_rotvec(rot)])


@pytest.fixture
def cell(roscore, start_sim):
    start_sim(HOST, "--cell", str(CELL), "--speed", "2", "--no-cameras", "--seed", str(SEED), "--sensor-rate", "50",
              env={"ROS_MASTER_URI": roscore})
    if not rospy.core.is_initialized():
        rospy.init_node("sim_test", anonymous=True, disable_signals=True)
    r = rtde_receive.RTDEReceiveInterface(HOST)
    c = rtde_control.RTDEControlInterface(HOST)
    io = rtde_io.RTDEIOInterface(HOST)
    yield c, r, io
    c.stopScript()
    for x in (io, c, r):
        x.disconnect()


def test_gripper_closes_on_cube_and_sensors_respond(cell):
    c, r, io = cell
    tactile = Latest(TACTILE_TOPIC, Scatter)
    wrench = Latest(WRENCH_TOPIC, WrenchStamped)
    replica = World(seed=SEED)  # same seed -> same part placement as in the sim process
    cube_pos, cube_orn = replica.body_poses()[0]
    replica.close()

    home = np.array(r.getActualTCPPose())
    above = grasp_pose(cube_pos, cube_orn, home[3:], 0.15)
    at = grasp_pose(cube_pos, cube_orn, home[3:], CUBE_SIZE / 2 + 0.012)
    io.setStandardDigitalOut(0, False)
    assert c.moveL(list(above), 0.4, 1.5)
    assert c.moveL(list(at), 0.15, 1.0)
    wait_for(c.isSteady, 3, what="steady at grasp")
    assert sum(tactile.fresh().y) == 0.0, "tactile pad must read nothing before grasping"
    f_before = np.array([wrench.fresh().wrench.force.x, wrench.msg.wrench.force.y, wrench.msg.wrench.force.z])

    assert io.setStandardDigitalOut(0, True)
    wait_for(lambda: r.getDigitalOutState(0), 2, what="DO0 reported high")
    wait_for(lambda: r.getActualDigitalInputBits() & 0b100, 5, what="part detected input (DI2)")
    wait_for(lambda: sum(tactile.fresh().y) > 5.0, 5, what="tactile pressure")
    t = tactile.msg
    assert len(t.x) == len(t.y) == 8
    assert max(t.y) > 1.0

    lift = at.copy()
    lift[2] += 0.12
    assert c.moveL(list(lift), 0.15, 1.0)
    wait_for(c.isSteady, 3, what="steady after lift")
    assert r.getActualDigitalInputBits() & 0b100, "cube slipped out of the gripper"
    # The pad's contact can drop for a physics step while the lift accelerates, and under CPU load such a reading
    # may still be queued after isSteady: await a pressed reading rather than take the next one.
    wait_for(lambda: sum(tactile.fresh().y) > 1.0, 3, what="tactile pressure with the cube lifted")
    w = wrench.fresh().wrench.force
    f_after = np.array([w.x, w.y, w.z])
    # The wrist now also carries the cube: ~0.1 kg * 9.81 m/s^2 more load.
    assert 0.6 < np.linalg.norm(f_after) - np.linalg.norm(f_before) < 1.5
    assert np.linalg.norm(r.getActualTCPForce()[:3]) > 9.0  # gripper + cube weight, reported over RTDE

    assert io.setStandardDigitalOut(0, False)
    wait_for(lambda: sum(tactile.fresh().y) == 0.0, 5, what="tactile released")
    wait_for(lambda: not r.getActualDigitalInputBits() & 0b100, 3, what="part released")
