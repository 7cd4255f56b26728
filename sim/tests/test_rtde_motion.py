"""Motion through the unmodified ur_rtde client against the emulated controller."""
from __future__ import annotations

import time

import numpy as np
import pytest

from conftest import wait_for
from sim import kinematics as kin

import rtde_control
import rtde_receive

SIM_HOST = "127.0.0.11"
SIM_ARGS = ["--speed", "2", "--no-cameras", "--no-ros"]
HOME = [0.0, -1.5708, 1.5708, -1.5708, -1.5708, 0.0]


@pytest.fixture(scope="module")
def robot(module_sim):
    r = rtde_receive.RTDEReceiveInterface(SIM_HOST)
    c = rtde_control.RTDEControlInterface(SIM_HOST)
    yield c, r
    c.stopScript()
    c.disconnect()
    r.disconnect()


def assert_same_pose(a, b, atol: float) -> None:
    """Poses as [x, y, z, rx, ry, rz]; near a half turn r and -r are the same rotation, so compare matrices."""
    a, b = np.asarray(a), np.asarray(b)
    np.testing.assert_allclose(a[:3], b[:3], atol=atol)
    np.testing.assert_allclose(kin.rotvec_to_matrix(a[3:]), kin.rotvec_to_matrix(b[3:]), atol=atol)


def test_receive_reports_a_running_arm(robot):
    c, r = robot
    assert r.getRobotMode() == 7            # RUNNING
    assert r.getSafetyMode() == 1           # NORMAL
    assert c.isProgramRunning()
    # PLAYING: the uploaded control script runs (this receiver's stream may trail the control client's)
    wait_for(lambda: r.getRuntimeState() == 2, 1, what="runtime_state PLAYING")
    wait_for(c.isSteady, 5, what="steady")
    q = np.array(r.getActualQ())
    assert_same_pose(r.getActualTCPPose(), kin.forward(q, c.getTCPOffset()), atol=1e-5)


def test_movej_reaches_target(robot):
    c, r = robot
    q0 = np.array(r.getActualQ())
    target = q0 + np.array([0.4, -0.2, 0.3, -0.2, 0.3, 0.5])
    t0 = time.monotonic()
    assert c.moveJ(list(target), 1.0, 2.0)
    assert time.monotonic() - t0 > 0.15  # it really moved at finite speed (0.5 rad at 1 rad/s, 2x real time)
    q = np.array(r.getActualQ())
    assert np.max(np.abs(q - target)) < 0.01
    assert np.max(np.abs(q - target)) < 1e-3  # tighter than the spec asks: the physics settles on the setpoint


def test_movel_accuracy_and_straight_line(robot):
    c, r = robot
    start = np.array(r.getActualTCPPose())
    goal = start + np.array([0.12, -0.08, -0.10, 0, 0, 0])
    samples: list[np.ndarray] = []
    assert c.moveL(list(goal), 0.25, 1.2, True)  # async, so we can sample the path
    wait_for(lambda: c.getAsyncOperationProgress() >= 0 or len(samples) > 0, 5, what="move start")
    deadline = time.monotonic() + 10
    while c.getAsyncOperationProgress() >= 0 and time.monotonic() < deadline:
        samples.append(np.array(r.getActualTCPPose()))
        time.sleep(0.005)
    wait_for(lambda: c.isSteady(), 5, what="steady")
    end = np.array(r.getActualTCPPose())
    assert np.linalg.norm(end[:3] - goal[:3]) < 1e-3
    rot_err = kin.matrix_to_rotvec(kin.rotvec_to_matrix(end[3:]) @ kin.rotvec_to_matrix(goal[3:]).T)
    assert np.linalg.norm(rot_err) < 0.01
    assert len(samples) > 20
    d = (goal - start)[:3] / np.linalg.norm((goal - start)[:3])
    deviation = max(np.linalg.norm((s[:3] - start[:3]) - np.dot(s[:3] - start[:3], d) * d) for s in samples)
    assert deviation < 2e-3, f"TCP left the straight line by {deviation * 1000:.2f} mm"


def test_movel_sync_with_rotation(robot):
    c, r = robot
    start = np.array(r.getActualTCPPose())
    m = kin.pose_to_matrix(start)
    m[:3, :3] = kin.rotvec_to_matrix([0, 0, 0.4]) @ m[:3, :3]
    m[:3, 3] += [0.0, 0.05, 0.05]
    goal = kin.matrix_to_pose(m)
    assert c.moveL(list(goal), 0.3, 1.5)
    end = np.array(r.getActualTCPPose())
    assert np.linalg.norm(end[:3] - goal[:3]) < 1e-3
    rot_err = kin.matrix_to_rotvec(kin.rotvec_to_matrix(end[3:]) @ kin.rotvec_to_matrix(goal[3:]).T)
    assert np.linalg.norm(rot_err) < 0.01


def test_async_movej_then_stopj(robot):
    c, r = robot
    q0 = np.array(r.getActualQ())
    target = q0 + np.array([1.2, 0, 0, 0, 0, 0])
    assert c.moveJ(list(target), 0.5, 1.0, True)
    wait_for(lambda: abs(r.getActualQ()[0] - q0[0]) > 0.1, 5, what="arm moving")
    assert c.getAsyncOperationProgress() >= 0  # still running
    c.stopJ(2.0)
    wait_for(lambda: c.isSteady(), 5, what="arm stopped")
    q = np.array(r.getActualQ())
    assert 0.1 < q[0] - q0[0] < 1.1, "stopJ should halt the arm between start and target"
    time.sleep(0.2)
    assert abs(r.getActualQ()[0] - q[0]) < 1e-3, "arm kept moving after stopJ"
    assert c.getAsyncOperationProgress() < 0
    assert c.moveJ(list(q0), 1.0, 2.0)  # and it accepts the next command


def test_speedj_moves_at_commanded_velocity(robot):
    c, r = robot
    qd = [0.2, 0, 0, 0, 0, -0.2]
    c.speedJ(qd, 1.0, 0.002)
    wait_for(lambda: abs(r.getActualQd()[0] - 0.2) < 0.01, 5, what="speedJ velocity")
    assert abs(r.getActualQd()[5] + 0.2) < 0.01
    c.speedStop(5.0)
    wait_for(lambda: max(abs(v) for v in r.getActualQd()) < 1e-3, 5, what="speedStop")


def test_speed_stop_uses_the_clients_deceleration(robot):
    """speedStop(a) decelerates at a (the script's stopj(a)/stopl(a)): a firm stop is quicker than a soft one."""
    c, r = robot

    def stop_time(a: float) -> float:
        c.speedJ([0.5, 0, 0, 0, 0, 0], 5.0, 0.002)
        wait_for(lambda: abs(r.getActualQd()[0] - 0.5) < 0.01, 5, what="speedJ velocity")
        t0 = r.getTimestamp()  # controller time
        c.speedStop(a)
        wait_for(lambda: abs(r.getActualQd()[0]) < 0.01, 5, interval=0.001, what="standstill")
        return r.getTimestamp() - t0

    soft, firm = stop_time(1.0), stop_time(20.0)
    assert 0.35 < soft < 0.7, f"0.5 rad/s at 1 rad/s^2 should take ~0.5 s, took {soft:.3f} s"
    assert firm < 0.1, f"0.5 rad/s at 20 rad/s^2 should take ~0.025 s, took {firm:.3f} s"


def test_speedl_moves_tcp_along_x(robot):
    c, r = robot
    p0 = np.array(r.getActualTCPPose())
    c.speedL([0.05, 0, 0, 0, 0, 0], 0.5, 0.002)
    wait_for(lambda: r.getActualTCPPose()[0] - p0[0] > 0.02, 5, what="speedL motion")
    c.speedStop(2.0)
    wait_for(lambda: c.isSteady(), 5, what="stopped")
    p = np.array(r.getActualTCPPose())
    assert abs(p[1] - p0[1]) < 2e-3 and abs(p[2] - p0[2]) < 2e-3


def test_servoj_tracks_streamed_targets(robot):
    c, r = robot
    q0 = np.array(r.getActualQ())
    for i in range(1, 301):
        k = min(i, 150)  # ramp for 150 periods, then keep streaming the final target
        target = q0 + np.array([0.002 * k, 0, 0, 0, 0, 0.002 * k])
        t0 = c.initPeriod()
        c.servoJ(list(target), 0.5, 0.5, 0.004, 0.1, 300)
        c.waitPeriod(t0)
    c.servoStop(5.0)
    wait_for(lambda: c.isSteady(), 5, what="servo stop")
    q = np.array(r.getActualQ())
    assert abs(q[0] - (q0[0] + 0.3)) < 0.01
    assert abs(q[5] - (q0[5] + 0.3)) < 0.01


def test_speed_slider_scales_motion_time(robot):
    import rtde_io
    c, r = robot
    io = rtde_io.RTDEIOInterface(SIM_HOST)
    try:
        q0 = r.getActualQ()
        q1 = list(np.array(q0) + [0.5, 0, 0, 0, 0, 0])
        t0 = r.getTimestamp()  # controller time: immune to wall-clock jitter
        assert c.moveJ(q1, 0.5, 3.0)
        full = r.getTimestamp() - t0
        assert io.setSpeedSlider(0.5)
        wait_for(lambda: abs(r.getTargetSpeedFraction() - 0.5) < 1e-6, 2, what="slider applied")
        t0 = r.getTimestamp()
        assert c.moveJ(q0, 0.5, 3.0)
        half = r.getTimestamp() - t0
        assert half > 1.4 * full, f"slider 0.5: {half:.2f}s vs {full:.2f}s at 1.0"
        assert np.max(np.abs(np.array(r.getActualQ()) - q0)) < 1e-3
    finally:
        io.setSpeedSlider(1.0)
        io.disconnect()


def test_inverse_kinematics_matches_forward(robot):
    c, r = robot
    q = np.array(r.getActualQ())
    pose = np.array(r.getActualTCPPose())
    pose[2] -= 0.05
    sol = np.array(c.getInverseKinematics(list(pose), list(q)))
    np.testing.assert_allclose(kin.forward(sol, c.getTCPOffset()), pose, atol=1e-6)
    assert np.max(np.abs(sol - q)) < 0.5  # the solution near the current configuration


def test_stop_script_ends_the_program(module_sim):
    c = rtde_control.RTDEControlInterface(SIM_HOST)
    r = rtde_receive.RTDEReceiveInterface(SIM_HOST)
    try:
        assert c.isProgramRunning()
        c.stopScript()
        wait_for(lambda: r.getRuntimeState() == 1, 5, what="program stopped")
        assert not c.isProgramRunning()
        assert not c.moveJ(r.getActualQ(), 1.0, 1.0), "commands must fail while no control script runs"
        assert c.reuploadScript()
        wait_for(c.isProgramRunning, 5, what="script re-uploaded")
        assert c.moveJ(r.getActualQ(), 1.0, 1.0)
    finally:
        c.disconnect()
        r.disconnect()


def test_upper_range_registers_and_waypoint_paths(module_sim):
    """FLAG_UPPER_RANGE_REGISTERS moves the protocol to registers 24+; moveJ/moveL paths are injected script."""
    flags = rtde_control.RTDEControlInterface.FLAG_UPPER_RANGE_REGISTERS | \
        rtde_control.RTDEControlInterface.FLAG_UPLOAD_SCRIPT
    c = rtde_control.RTDEControlInterface(SIM_HOST, 500.0, flags)
    r = rtde_receive.RTDEReceiveInterface(SIM_HOST)
    try:
        assert c.moveJ(HOME, 1.5, 3.0)  # known start, well away from singularities
        q0 = np.array(r.getActualQ())
        assert c.moveJ(list(q0 + [0.15, 0, 0, 0, 0, 0]), 1.0, 2.0)
        assert np.max(np.abs(np.array(r.getActualQ()) - q0 - [0.15, 0, 0, 0, 0, 0])) < 1e-3
        path = [list(q0 + [0.05, 0, 0, 0, 0, 0]) + [1.0, 2.0, 0.0],
                list(q0 + [0.05, -0.1, 0.1, 0, 0, 0]) + [1.0, 2.0, 0.0]]
        assert c.moveJ(path)
        assert np.max(np.abs(np.array(r.getActualQ()) - q0 - [0.05, -0.1, 0.1, 0, 0, 0])) < 1e-3
        p = np.array(r.getActualTCPPose())
        lpath = [list(p + [0.03, 0, 0, 0, 0, 0]) + [0.2, 1.0, 0.0],
                 list(p + [0.03, 0.03, 0, 0, 0, 0]) + [0.2, 1.0, 0.0]]
        assert c.moveL(lpath)
        assert np.linalg.norm(np.array(r.getActualTCPPose())[:3] - p[:3] - [0.03, 0.03, 0]) < 1e-3
        assert_same_pose(c.getForwardKinematics(), r.getActualTCPPose(), atol=1e-4)
    finally:
        c.stopScript()
        c.disconnect()
        r.disconnect()

