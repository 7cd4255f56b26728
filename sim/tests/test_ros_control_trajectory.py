"""The joint_trajectory_controller logic of the ros_control sim (sim/ros_control/trajectory.py), without ROS:
validation and error codes, interpolation, tolerance aborts, preemption, cancel, topic commands, empty = hold."""
from __future__ import annotations

import numpy as np
import pytest

from sim.ros_control.trajectory import (GOAL_TOLERANCE_VIOLATED, INVALID_GOAL, INVALID_JOINTS,
                                        PATH_TOLERANCE_VIOLATED, SUCCESSFUL, Defaults, JointTolerance, Point,
                                        Tolerance, TrajectoryController)

J = ("j1", "j2", "j3")
DT = 0.002


def controller(q0=(0.0, 0.0, 0.0)) -> TrajectoryController:
    ctl = TrajectoryController(J, Defaults(path=Tolerance(0.1), goal=Tolerance(0.01, 0.05), goal_time=0.5))
    ctl.hold(0.0, q0)
    return ctl


def run(ctl: TrajectoryController, t0: float, t1: float, follow: bool = True, actual=None):
    """Step the controller from t0 to t1; the 'arm' follows the desired state exactly unless follow is False
    (then it stays at `actual`). Returns (events with their times, last time)."""
    events = []
    q = np.array(actual if actual is not None else ctl.desired[0])
    qd = np.zeros(len(J))
    t = t0
    while t <= t1 + 1e-9:
        q_des, qd_des, evs = ctl.update(t, q, qd)
        events += [(t, e) for e in evs]
        if follow:
            q, qd = q_des.copy(), qd_des.copy()
        t += DT
    return events, t


# ---- validation ---------------------------------------------------------------------------------------------
@pytest.mark.parametrize("names", [("j1", "j2"), ("j1", "j2", "x"), ("j1", "j1", "j2"), ("j1", "j2", "j3", "j4")])
def test_wrong_joint_names_are_rejected_with_invalid_joints(names):
    ctl = controller()
    out = ctl.submit_goal("g", names, [Point(1.0, [0.0] * len(names))], 0.0, 0.0)
    assert not out.accepted and out.code == INVALID_JOINTS
    assert "do not match" in out.text and "j1" in out.text


@pytest.mark.parametrize("points, words", [
    ([Point(1.0, [0, 0])], "2 positions for 3 joints"),
    ([Point(1.0, [0, 0, 0], velocities=[0])], "1 velocities"),
    ([Point(1.0, [0, 0, 0]), Point(1.0, [1, 1, 1])], "strictly greater"),
    ([Point(1.0, [0, 0, 0]), Point(0.5, [1, 1, 1])], "strictly greater"),
    ([Point(-0.1, [0, 0, 0])], ">= 0"),
    ([Point(1.0, [0, float("nan"), 0])], "not finite"),
])
def test_malformed_points_are_rejected_with_invalid_goal(points, words):
    out = controller().submit_goal("g", J, points, 0.0, 0.0)
    assert not out.accepted and out.code == INVALID_GOAL and words in out.text


def test_a_trajectory_entirely_in_the_past_is_rejected():
    out = controller().submit_goal("g", J, [Point(1.0, [1, 1, 1])], start=5.0, now=10.0)
    assert not out.accepted and out.code == INVALID_GOAL and "past" in out.text


# ---- sampling -----------------------------------------------------------------------------------------------
def test_joint_names_in_any_order_are_mapped_to_the_controllers_order():
    ctl = controller()
    assert ctl.submit_goal("g", ("j3", "j1", "j2"), [Point(1.0, [3.0, 1.0, 2.0])], 0.0, 0.0).accepted
    q, qd, _ = ctl.update(2.0, [1.0, 2.0, 3.0], [0, 0, 0])
    assert np.allclose(q, [1.0, 2.0, 3.0]) and np.allclose(qd, 0)


def test_cubic_segments_hit_positions_and_velocities_at_the_points():
    ctl = controller()
    pts = [Point(1.0, [1.0, 0.5, -0.5], [0.5, 0.0, 0.0]), Point(2.0, [1.5, 0.5, -1.0], [0.0, 0.0, 0.0])]
    assert ctl.submit_command(J, pts, 0.0, 0.0, q_actual=[0] * 3).accepted  # no tolerances: sampling only
    samples = {t: ctl.update(t, [0] * 3, [0] * 3)[:2] for t in (0.0, 0.5, 1.0, 2.0, 3.0)}
    assert np.allclose(samples[0.0][0], 0) and np.allclose(samples[0.0][1], 0)  # starts from the desired state
    assert np.allclose(samples[1.0][0], [1.0, 0.5, -0.5]) and np.allclose(samples[1.0][1], [0.5, 0, 0])
    assert np.allclose(samples[2.0][0], [1.5, 0.5, -1.0]) and np.allclose(samples[2.0][1], 0)
    assert np.allclose(samples[3.0][0], [1.5, 0.5, -1.0]) and np.allclose(samples[3.0][1], 0)  # after: hold
    # cubic from (0, v0=0) to (1, v1=0.5) over 1 s: q(s) = (3 - 0.5) s^2 + (-2 + 0.5) s^3; q(0.5) = 0.4375
    assert samples[0.5][0][0] == pytest.approx(0.4375)


def test_quintic_segments_when_accelerations_are_given():
    ctl = controller()
    pts = [Point(2.0, [1.0, 1.0, 1.0], [0, 0, 0], [0, 0, 0])]
    assert ctl.submit_goal("g", J, pts, 0.0, 0.0).accepted
    q, qd, _ = ctl.update(1.0, [0.5] * 3, [0] * 3)
    assert np.allclose(q, 0.5) and np.allclose(qd, 15 / 16)  # minimum-jerk midpoint: 1.875 * mean speed
    _, _, qdd = ctl._traj.sample(1.999999)
    assert np.allclose(qdd, 0, atol=1e-3)


def test_positions_only_interpolate_linearly():
    ctl = controller()
    assert ctl.submit_command(J, [Point(2.0, [2.0, 0.0, -2.0])], 0.0, 0.0, q_actual=[0] * 3).accepted
    q, qd, _ = ctl.update(0.5, [0] * 3, [0] * 3)
    assert np.allclose(q, [0.5, 0, -0.5]) and np.allclose(qd, [1, 0, -1])


def test_header_stamp_in_the_future_and_points_in_the_past():
    ctl = controller()
    # start 1 s from now: the arm waits at the desired state, then moves
    assert ctl.submit_command(J, [Point(1.0, [1.0, 1.0, 1.0])], start=1.0, now=0.0, q_actual=[0] * 3).accepted
    assert np.allclose(ctl.update(0.9, [0] * 3, [0] * 3)[0], 0.45)  # linear from now (0) to t=2
    # a command whose first point already lies in the past: that point is dropped
    ctl = controller()
    out = ctl.submit_command(J, [Point(0.5, [9.0] * 3), Point(2.0, [1.0] * 3)], start=0.0, now=1.0, q_actual=[0] * 3)
    assert out.accepted
    q, _, _ = ctl.update(1.5, [0] * 3, [0] * 3)
    assert np.allclose(q, 0.5)  # halfway from the current state (0) to the point at t=2


# ---- goals ending -------------------------------------------------------------------------------------------
def test_a_followed_goal_succeeds_after_its_last_point():
    ctl = controller()
    assert ctl.submit_goal("g", J, [Point(1.0, [0.3, 0.2, 0.1], [0, 0, 0])], 0.0, 0.0).accepted
    events, _ = run(ctl, 0.0, 1.5)
    assert [(e.goal, e.status, e.code) for _, e in events] == [("g", "succeeded", SUCCESSFUL)]
    assert events[0][0] == pytest.approx(1.0, abs=2 * DT)
    assert ctl.active_goal is None


def test_an_arm_that_cannot_follow_aborts_with_path_tolerance_violated_and_holds():
    ctl = controller()
    assert ctl.submit_goal("g", J, [Point(1.0, [1.0, 0.0, 0.0])], 0.0, 0.0).accepted
    events, _ = run(ctl, 0.0, 1.0, follow=False, actual=[0.0, 0.0, 0.0])
    assert len(events) == 1
    t, ev = events[0]
    assert ev.status == "aborted" and ev.code == PATH_TOLERANCE_VIOLATED
    assert "j1" in ev.text and "0.1000" in ev.text
    assert t == pytest.approx(0.1, abs=3 * DT)  # linear at 1 rad/s: 0.1 rad behind after 0.1 s
    q, qd, _ = ctl.update(t + 0.5, [0.0, 0.0, 0.0], [0, 0, 0])
    assert np.allclose(q, 0) and np.allclose(qd, 0)  # holds where the arm is


def test_path_tolerance_from_the_goal_overrides_and_minus_one_disables():
    ctl = controller()
    tol = [JointTolerance("j1", position=0.5)]
    assert ctl.submit_goal("g", J, [Point(1.0, [1.0, 0, 0])], 0.0, 0.0, path_tolerance=tol).accepted
    events, _ = run(ctl, 0.0, 0.99, follow=False, actual=[0, 0, 0])
    assert events and events[0][0] == pytest.approx(0.5, abs=3 * DT)
    ctl = controller()
    tol = [JointTolerance("j1", position=-1)]
    assert ctl.submit_goal("g", J, [Point(1.0, [1.0, 0, 0])], 0.0, 0.0, path_tolerance=tol,
                           goal_tolerance=[JointTolerance("j1", position=-1)]).accepted
    events, _ = run(ctl, 0.0, 2.0, follow=False, actual=[0, 0, 0])
    assert [e.status for _, e in events] == ["succeeded"]  # nothing checked on j1 at all


def test_goal_tolerance_violated_after_goal_time_tolerance():
    ctl = controller()
    tol = [JointTolerance(j, position=-1) for j in J]
    assert ctl.submit_goal("g", J, [Point(1.0, [0.05, 0, 0])], 0.0, 0.0, path_tolerance=tol,
                           goal_time_tolerance=0.3).accepted
    events, _ = run(ctl, 0.0, 2.0, follow=False, actual=[0, 0, 0])
    assert len(events) == 1
    t, ev = events[0]
    assert ev.code == GOAL_TOLERANCE_VIOLATED and "j1" in ev.text and "0.0100" in ev.text
    assert t == pytest.approx(1.3, abs=3 * DT)


def test_a_late_arrival_within_goal_time_tolerance_succeeds():
    ctl = controller()
    assert ctl.submit_goal("g", J, [Point(1.0, [0.05, 0, 0])], 0.0, 0.0, goal_time_tolerance=0.3).accepted
    events, t = run(ctl, 0.0, 1.1, follow=False, actual=[0, 0, 0])
    assert events == []
    _, _, evs = ctl.update(t, [0.05, 0, 0], [0, 0, 0])
    assert [e.status for e in evs] == ["succeeded"]


# ---- replacing what runs ------------------------------------------------------------------------------------
def test_a_new_goal_preempts_the_running_one_and_continues_from_the_desired_state():
    ctl = controller()
    assert ctl.submit_goal("g1", J, [Point(2.0, [2.0, 0, 0])], 0.0, 0.0).accepted
    run(ctl, 0.0, 1.0)
    q_before = ctl.desired[0].copy()
    out = ctl.submit_goal("g2", J, [Point(1.0, [0.0, 0, 0])], 1.0, 1.0)
    assert out.accepted and out.preempted == "g1"
    assert ctl.active_goal == "g2"
    q, _, _ = ctl.update(1.0, q_before, [1, 0, 0])
    assert np.allclose(q, q_before)  # no jump
    # a rejected goal leaves the running one alone
    out = ctl.submit_goal("g3", ("a", "b", "c"), [Point(1.0, [0, 0, 0])], 1.0, 1.0)
    assert not out.accepted and out.preempted is None and ctl.active_goal == "g2"


def test_a_topic_command_preempts_the_goal():
    ctl = controller()
    assert ctl.submit_goal("g", J, [Point(2.0, [2.0, 0, 0])], 0.0, 0.0).accepted
    out = ctl.submit_command(J, [Point(0.5, [0.1, 0.1, 0.1])], 0.5, 0.5, q_actual=[0.5, 0, 0])
    assert out.accepted and out.preempted == "g" and ctl.active_goal is None
    # topic commands have no tolerances: an arm that does not follow ends nothing
    events, _ = run(ctl, 0.5, 2.0, follow=False, actual=[5.0, 5.0, 5.0])
    assert events == []


def test_an_empty_command_holds_the_current_position_at_once():
    ctl = controller()
    assert ctl.submit_command(J, [Point(2.0, [2.0, 0, 0])], 0.0, 0.0, q_actual=[0, 0, 0]).accepted
    run(ctl, 0.0, 1.0)
    out = ctl.submit_command(J, [], 1.0, 1.0, q_actual=[0.95, 0.0, 0.0])
    assert out.accepted
    for t in (1.0, 1.5, 3.0):
        q, qd, _ = ctl.update(t, [0.95, 0, 0], [0, 0, 0])
        assert np.allclose(q, [0.95, 0, 0]) and np.allclose(qd, 0)


def test_an_empty_goal_stops_and_succeeds():
    ctl = controller()
    assert ctl.submit_goal("g1", J, [Point(2.0, [2.0, 0, 0])], 0.0, 0.0).accepted
    run(ctl, 0.0, 1.0)
    out = ctl.submit_goal("g2", J, [], 1.0, 1.0, q_actual=[0.5, 0, 0])
    assert out.accepted and out.preempted == "g1"
    _, _, evs = ctl.update(1.002, [0.5, 0, 0], [0, 0, 0])
    assert [(e.goal, e.status) for e in evs] == [("g2", "succeeded")]


def test_cancel_holds_the_actual_position_and_only_cancels_the_running_goal():
    ctl = controller()
    assert ctl.submit_goal("g", J, [Point(2.0, [2.0, 0, 0])], 0.0, 0.0).accepted
    assert not ctl.cancel("other", 1.0, [0.9, 0, 0])
    assert ctl.cancel("g", 1.0, [0.9, 0, 0])
    assert ctl.active_goal is None
    q, qd, evs = ctl.update(1.5, [0.9, 0, 0], [0, 0, 0])
    assert np.allclose(q, [0.9, 0, 0]) and np.allclose(qd, 0) and evs == []


def test_abort_ends_the_running_goal_with_path_tolerance_violated():
    ctl = controller()
    assert ctl.abort(0.0, [0, 0, 0], "x") is None  # nothing running
    assert ctl.submit_goal("g", J, [Point(2.0, [2.0, 0, 0])], 0.0, 0.0).accepted
    ev = ctl.abort(0.5, [0.2, 0, 0], "blocked")
    assert ev.goal == "g" and ev.code == PATH_TOLERANCE_VIOLATED and ev.text == "blocked"
    assert np.allclose(ctl.update(1.0, [0.2, 0, 0], [0] * 3)[0], [0.2, 0, 0])
