"""The joint_trajectory_controller of ros_control (ros_controllers' JointTrajectoryController), in plain Python.

What a real ros_control driver (iiwa_stack's PositionJointInterface_trajectory_controller) does with the goals of its
control_msgs/FollowJointTrajectory action and the trajectories on its command topic, so the sim's driver behaves
like it. No ROS here: the rospy layer (driver.py) converts messages to Point/JointTolerance lists and applies the
outcomes to actionlib goal handles.

Semantics (as JointTrajectoryController, allow_partial_joints_goal false):
- a goal must name exactly the controller's joints, in any order: else rejected with INVALID_JOINTS;
- every point has one position per joint (velocities/accelerations empty or one per joint) and time_from_start
  strictly increasing: else rejected with INVALID_GOAL, as is a trajectory whose points all lie in the past;
- the trajectory starts at header.stamp (0: now); points before now are dropped; the first segment runs from the
  current desired state; segments are linear (positions only), cubic (+ velocities) or quintic (+ accelerations);
  after the last point: its position, zero velocity;
- a new goal or a topic command replaces the running trajectory; the running goal ends PREEMPTED; a cancel holds
  the current (actual) position; an empty trajectory on the command topic holds the current position at once;
- while the trajectory runs, |desired - actual| above a joint's path tolerance aborts the goal with
  PATH_TOLERANCE_VIOLATED and holds the current position; from the last point's time on, the goal succeeds once
  every joint is within its goal tolerance, and aborts with GOAL_TOLERANCE_VIOLATED if that has not happened by
  goal_time_tolerance later. Tolerances: > 0 sets, 0 keeps the controller's default, < 0 means none.
  Topic commands have no tolerances (as in ros_control).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Optional, Sequence

import numpy as np

SUCCESSFUL = 0
INVALID_GOAL = -1
INVALID_JOINTS = -2
OLD_HEADER_TIMESTAMP = -3
PATH_TOLERANCE_VIOLATED = -4
GOAL_TOLERANCE_VIOLATED = -5


@dataclass(frozen=True)
class Point:
    time: float                               # time_from_start (s)
    positions: Sequence[float]
    velocities: Sequence[float] = ()
    accelerations: Sequence[float] = ()


@dataclass(frozen=True)
class JointTolerance:
    name: str
    position: float = 0.0
    velocity: float = 0.0
    acceleration: float = 0.0                 # accepted, not checked (the sim measures no acceleration)


@dataclass(frozen=True)
class Tolerance:
    position: float = 0.0                     # 0: not checked
    velocity: float = 0.0


@dataclass(frozen=True)
class Defaults:
    """The controller's configured constraints (iiwa_stack-like `constraints:`): per joint trajectory and goal
    position tolerance, stopped velocity tolerance, goal_time."""
    path: Tolerance = Tolerance(position=0.1)
    goal: Tolerance = Tolerance(position=0.01, velocity=0.05)
    goal_time: float = 0.5


@dataclass(frozen=True)
class Outcome:
    """What became of a request: accepted or rejected (code, text), and the goal it preempted, if any."""
    accepted: bool
    code: int = SUCCESSFUL
    text: str = ""
    preempted: Optional[object] = None


@dataclass(frozen=True)
class GoalEvent:
    """A running goal ended by itself: status 'succeeded' or 'aborted'."""
    goal: object
    status: str
    code: int
    text: str


@dataclass
class _Knot:
    t: float
    q: np.ndarray
    v: Optional[np.ndarray]
    a: Optional[np.ndarray]


class Trajectory:
    """Piecewise polynomial through knots (absolute times). Sampling before the first knot gives its state."""

    def __init__(self, knots: list[_Knot]) -> None:
        self.knots = knots
        self.coeffs: list[np.ndarray] = []   # per segment: (6, n) coefficients of s^0..s^5
        for k0, k1 in zip(knots, knots[1:]):
            self.coeffs.append(_coefficients(k0, k1))

    @property
    def end_time(self) -> float:
        return self.knots[-1].t

    def sample(self, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        first, last = self.knots[0], self.knots[-1]
        n = len(first.q)
        if t <= first.t or len(self.knots) == 1:
            k = first if t <= first.t else last
            v = k.v if (k is first and k.v is not None and len(self.knots) > 1) else np.zeros(n)
            return k.q.copy(), v.copy(), np.zeros(n)
        if t >= last.t:
            return last.q.copy(), np.zeros(n), np.zeros(n)
        i = max(j for j in range(len(self.knots) - 1) if self.knots[j].t <= t)
        c = self.coeffs[i]
        s = t - self.knots[i].t
        pw = np.array([1, s, s ** 2, s ** 3, s ** 4, s ** 5])
        dp = np.array([0, 1, 2 * s, 3 * s ** 2, 4 * s ** 3, 5 * s ** 4])
        ddp = np.array([0, 0, 2, 6 * s, 12 * s ** 2, 20 * s ** 3])
        return pw @ c, dp @ c, ddp @ c


def _coefficients(k0: _Knot, k1: _Knot) -> np.ndarray:
    """Linear (positions only), cubic (both ends with velocities) or quintic (and accelerations)."""
    T = k1.t - k0.t
    n = len(k0.q)
    c = np.zeros((6, n))
    c[0] = k0.q
    if T <= 1e-12:
        c[0] = k1.q  # a zero-length segment (a point at "now"): jump to it
        return c
    dq = k1.q - k0.q
    if k0.v is None or k1.v is None:
        c[1] = dq / T
    elif k0.a is None or k1.a is None:
        c[1] = k0.v
        c[2] = (3 * dq - (2 * k0.v + k1.v) * T) / T ** 2
        c[3] = (-2 * dq + (k0.v + k1.v) * T) / T ** 3
    else:
        v0, v1, a0, a1 = k0.v, k1.v, k0.a, k1.a
        c[1], c[2] = v0, a0 / 2
        c[3] = (20 * dq - (8 * v1 + 12 * v0) * T - (3 * a0 - a1) * T ** 2) / (2 * T ** 3)
        c[4] = (-30 * dq + (14 * v1 + 16 * v0) * T + (3 * a0 - 2 * a1) * T ** 2) / (2 * T ** 4)
        c[5] = (12 * dq - 6 * (v1 + v0) * T - (a0 - a1) * T ** 2) / (2 * T ** 5)
    return c


@dataclass
class _Goal:
    handle: object
    path: list[Tolerance]
    goal: list[Tolerance]
    goal_time: float
    end_time: float


@dataclass
class TrajectoryController:
    joints: Sequence[str]
    defaults: Defaults = field(default_factory=Defaults)

    def __post_init__(self) -> None:
        self.joints = tuple(self.joints)
        self.n = len(self.joints)
        self._traj = Trajectory([_Knot(0.0, np.zeros(self.n), None, None)])
        self._goal: Optional[_Goal] = None
        self.desired = (np.zeros(self.n), np.zeros(self.n), np.zeros(self.n))

    # ---- requests (from the ROS callbacks; the caller serialises them with update) ----------------------
    @property
    def active_goal(self) -> Optional[object]:
        return self._goal.handle if self._goal else None

    def hold(self, now: float, q: Sequence[float]) -> None:
        """Hold this position from now on (the controller starting, a stop). Does not end a goal."""
        q = np.asarray(q, dtype=float)
        self._traj = Trajectory([_Knot(now, q.copy(), np.zeros(self.n), np.zeros(self.n))])
        self.desired = (q.copy(), np.zeros(self.n), np.zeros(self.n))

    def validate(self, names: Sequence[str], points: Sequence[Point]) -> tuple[int, str, Optional[list[int]]]:
        """(code, text, index of each controller joint in the message's order)."""
        if len(names) != self.n or len(set(names)) != len(names) or set(names) != set(self.joints):
            return INVALID_JOINTS, (f"joints {list(names)} do not match the controller's joints "
                                    f"{list(self.joints)}"), None
        order = [list(names).index(j) for j in self.joints]
        last = -math.inf
        for i, p in enumerate(points):
            if len(p.positions) != self.n:
                return INVALID_GOAL, f"point {i}: {len(p.positions)} positions for {self.n} joints", None
            for what, vals in (("velocities", p.velocities), ("accelerations", p.accelerations)):
                if len(vals) not in (0, self.n):
                    return INVALID_GOAL, f"point {i}: {len(vals)} {what} for {self.n} joints", None
            if not all(math.isfinite(v) for v in (*p.positions, *p.velocities, *p.accelerations)):
                return INVALID_GOAL, f"point {i}: a value is not finite", None
            if p.time < 0 or p.time <= last:
                return INVALID_GOAL, (f"point {i}: time_from_start {p.time:.4f} s must be >= 0 and strictly greater "
                                      f"than the previous point's"), None
            last = p.time
        return SUCCESSFUL, "", order

    def submit_goal(self, handle: object, names: Sequence[str], points: Sequence[Point], start: float, now: float,
                    path_tolerance: Sequence[JointTolerance] = (), goal_tolerance: Sequence[JointTolerance] = (),
                    goal_time_tolerance: float = 0.0, q_actual: Optional[Sequence[float]] = None) -> Outcome:
        """An action goal; start: header.stamp as controller time (now when the stamp is 0)."""
        if not points:
            # An empty goal is a stop request (as JTC's updateTrajectoryCommand); it succeeds at once, holding.
            code, text, _ = self.validate(names, points)
            if code != SUCCESSFUL:
                return Outcome(False, code, text)
            preempted = self._end_goal()
            self.hold(now, self.desired[0] if q_actual is None else q_actual)
            traj = self._traj  # the goal ends like any other: once its (hold) end state is reached
        else:
            traj, code, text = self._build(names, points, start, now)
            if traj is None:
                return Outcome(False, code, text)
            preempted = self._end_goal()
        path = self._tolerances(path_tolerance, self.defaults.path)
        goal = self._tolerances(goal_tolerance, self.defaults.goal)
        self._traj = traj
        self._goal = _Goal(handle, path, goal, goal_time_tolerance if goal_time_tolerance > 0
                           else self.defaults.goal_time, traj.end_time)
        return Outcome(True, preempted=preempted)

    def submit_command(self, names: Sequence[str], points: Sequence[Point], start: float, now: float,
                       q_actual: Sequence[float]) -> Outcome:
        """The command topic: replaces whatever runs; empty = hold the current position at once."""
        if not points:
            preempted = self._end_goal()
            self.hold(now, q_actual)
            return Outcome(True, SUCCESSFUL, "empty trajectory: holding", preempted)
        traj, code, text = self._build(names, points, start, now)
        if traj is None:
            return Outcome(False, code, text)
        preempted = self._end_goal()
        self._traj = traj
        return Outcome(True, preempted=preempted)

    def cancel(self, handle: object, now: float, q_actual: Sequence[float]) -> bool:
        """Cancel this goal if it is the running one (then hold the current position): True if it was."""
        if self._goal is None or self._goal.handle != handle:  # actionlib's handles compare by goal id
            return False
        self._goal = None
        self.hold(now, q_actual)
        return True

    def abort(self, now: float, q_actual: Sequence[float], text: str) -> Optional[GoalEvent]:
        """End the running goal with PATH_TOLERANCE_VIOLATED and hold (e.g. the arm was stopped by a fault)."""
        goal = self._end_goal()
        self.hold(now, q_actual)
        return GoalEvent(goal, "aborted", PATH_TOLERANCE_VIOLATED, text) if goal is not None else None

    # ---- the control cycle ------------------------------------------------------------------------------
    def update(self, now: float, q: Sequence[float], qd: Sequence[float]
               ) -> tuple[np.ndarray, np.ndarray, list[GoalEvent]]:
        """One cycle: the desired position and velocity to command, and the goals that ended."""
        q, qd = np.asarray(q, dtype=float), np.asarray(qd, dtype=float)
        events: list[GoalEvent] = []
        self.desired = self._traj.sample(now)
        g = self._goal
        if g is not None:
            if now < g.end_time:
                bad = self._violation(g.path, q, qd)
                if bad:
                    events.append(GoalEvent(g.handle, "aborted", PATH_TOLERANCE_VIOLATED,
                                            f"path tolerance violated: {bad}"))
                    self._goal = None
                    self.hold(now, q)
            else:
                bad = self._violation(g.goal, q, qd)
                if not bad:
                    events.append(GoalEvent(g.handle, "succeeded", SUCCESSFUL, ""))
                    self._goal = None
                elif now > g.end_time + g.goal_time:
                    events.append(GoalEvent(g.handle, "aborted", GOAL_TOLERANCE_VIOLATED,
                                            f"goal tolerance violated {now - g.end_time:.3f} s after the trajectory's "
                                            f"end (goal_time_tolerance {g.goal_time:.3f} s): {bad}"))
                    self._goal = None
        return self.desired[0], self.desired[1], events

    # ---- helpers ----------------------------------------------------------------------------------------
    def _end_goal(self) -> Optional[object]:
        handle = self._goal.handle if self._goal else None
        self._goal = None
        return handle

    def _tolerances(self, given: Sequence[JointTolerance], default: Tolerance) -> list[Tolerance]:
        out = [default] * self.n
        for tol in given:
            if tol.name not in self.joints:
                continue  # as JTC: tolerances for other joints are ignored
            i = self.joints.index(tol.name)
            pos = out[i].position if tol.position == 0 else max(tol.position, 0.0)
            vel = out[i].velocity if tol.velocity == 0 else max(tol.velocity, 0.0)
            out[i] = Tolerance(pos, vel)
        return out

    def _violation(self, tols: list[Tolerance], q: np.ndarray, qd: np.ndarray) -> str:
        """'' when every joint is within its tolerance, else which joint is off and by how much."""
        dq, dv = self.desired[0] - q, self.desired[1] - qd
        for i, t in enumerate(tols):
            if t.position > 0 and abs(dq[i]) > t.position:
                return (f"{self.joints[i]} position error {dq[i]:+.4f} rad exceeds the tolerance "
                        f"{t.position:.4f} rad (desired {self.desired[0][i]:.4f}, actual {q[i]:.4f})")
            if t.velocity > 0 and abs(dv[i]) > t.velocity:
                return (f"{self.joints[i]} velocity error {dv[i]:+.4f} rad/s exceeds the tolerance "
                        f"{t.velocity:.4f} rad/s")
        return ""

    def _build(self, names: Sequence[str], points: Sequence[Point], start: float, now: float
               ) -> tuple[Optional[Trajectory], int, str]:
        code, text, order = self.validate(names, points)
        if code != SUCCESSFUL:
            return None, code, text
        if start + points[-1].time < now:
            return None, INVALID_GOAL, (f"all {len(points)} trajectory points lie in the past (the last "
                                        f"{now - start - points[-1].time:.3f} s ago)")
        q0, v0, a0 = self._traj.sample(now)  # the current desired state: the trajectory continues from it
        knots = [_Knot(now, q0, v0, a0)]
        for p in points:
            t = start + p.time
            if t < now:
                continue  # already past: dropped
            pick = (lambda vals: np.array([vals[k] for k in order], dtype=float) if len(vals) else None)
            knots.append(_Knot(t, pick(p.positions), pick(p.velocities), pick(p.accelerations)))
        return Trajectory(knots), SUCCESSFUL, ""
