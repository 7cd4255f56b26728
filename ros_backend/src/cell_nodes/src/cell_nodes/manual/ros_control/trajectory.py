"""What goes into a FollowJointTrajectory goal (or the controller's command topic), as plain data: joint moves,
straight-line TCP moves and the streamed points of a jog. No ROS here; the backend turns the points into
trajectory_msgs/JointTrajectoryPoint.

Points carry positions and velocities (the joint_trajectory_controller then interpolates cubically between them).
The start point (time 0, the current position) is left out: the controller starts from its current desired state
anyway, and a point at time 0 that differs a little from that state makes it jump. Sample times include the
profile's phase changes, so a cubic between two samples reproduces the trapezoid exactly (no overshoot of the
speed between samples).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple, Optional, Sequence

import numpy as np

from .. import frames
from ..limits import TCP_COMMAND_MARGIN, TCP_SPEED_CAP
from .kinematics import Kinematics

SAMPLE_TIME = 0.02                  # s between points of a joint move
MAX_STEP = 0.005                    # m between waypoints of a linear move
MAX_STEP_ANGLE = math.radians(2.0)  # rad between waypoints of a linear move
# A joint turning more than this between two waypoints (5 mm / 2 deg apart) means a configuration flip or a
# singularity on the line: a joint would have to race (or jump) to keep the TCP on it. Typical steps are < 0.05.
MAX_JOINT_STEP = 0.25               # rad
_CHECK_TAUS = (0.25, 0.5, 0.75)     # where the cubic between two points is checked against the caps
_TIMING_PASSES = 6                  # stretch-and-check rounds of linear_move's timing


class TrajectoryError(ValueError):
    """A motion that cannot be built; the message is meant for the operator."""


@dataclass(frozen=True)
class TrajectoryPoint:
    positions: list[float]
    velocities: list[float]
    time_from_start: float          # s


@dataclass(frozen=True)
class Trapezoid:
    """A trapezoidal (or triangular) speed profile over a path of `length` from rest to rest."""
    length: float
    peak: float                     # the speed actually reached
    acceleration: float
    t_acc: float                    # s accelerating (and as long decelerating)
    t_flat: float                   # s at the peak speed

    @classmethod
    def plan(cls, length: float, speed: float, acceleration: float) -> "Trapezoid":
        if not (speed > 0 and acceleration > 0 and math.isfinite(speed) and math.isfinite(acceleration)):
            raise TrajectoryError(f"speed and acceleration must be positive (got {speed:g}, {acceleration:g})")
        if length <= 0:
            return cls(0.0, 0.0, acceleration, 0.0, 0.0)
        if length <= speed * speed / acceleration:      # never reaches the speed: a triangle
            peak = math.sqrt(length * acceleration)
            return cls(length, peak, acceleration, peak / acceleration, 0.0)
        return cls(length, speed, acceleration, speed / acceleration, (length - speed * speed / acceleration) / speed)

    @property
    def duration(self) -> float:
        return 2 * self.t_acc + self.t_flat

    @property
    def s_acc(self) -> float:
        return 0.5 * self.acceleration * self.t_acc ** 2

    def at(self, t: float) -> tuple[float, float]:
        """(distance, speed) at time t."""
        a, ta, T = self.acceleration, self.t_acc, self.duration
        if t <= 0:
            return 0.0, 0.0
        if t >= T:
            return self.length, 0.0
        if t < ta:
            return 0.5 * a * t * t, a * t
        if t <= ta + self.t_flat:
            return self.s_acc + self.peak * (t - ta), self.peak
        r = T - t
        return self.length - 0.5 * a * r * r, a * r

    def time_at(self, s: float) -> float:
        """The time the profile reaches distance s (the inverse of `at`)."""
        a, sa = self.acceleration, self.s_acc
        if s <= 0:
            return 0.0
        if s >= self.length:
            return self.duration
        if s < sa:
            return math.sqrt(2 * s / a)
        if s <= self.length - sa:
            return self.t_acc + (s - sa) / self.peak
        return self.duration - math.sqrt(2 * (self.length - s) / a)

    def sample_times(self, dt: float) -> list[float]:
        """Times in (0, duration], at most dt apart, including the phase changes."""
        marks = [0.0, self.t_acc, self.t_acc + self.t_flat, self.duration]
        out: list[float] = []
        for a, b in zip(marks, marks[1:]):
            if b - a <= 1e-12:
                continue
            n = max(1, math.ceil((b - a) / dt - 1e-9))
            out.extend(a + (b - a) * k / n for k in range(1, n + 1))
        return out


def _vector(values: Sequence[float], n: Optional[int], what: str) -> np.ndarray:
    v = np.asarray(values, dtype=float)
    if v.ndim != 1 or (n is not None and len(v) != n) or not np.all(np.isfinite(v)):
        want = f"{n} finite numbers" if n is not None else "finite numbers"
        raise TrajectoryError(f"{what}: expected {want}, got {list(values)!r}")
    return v


def _positive(x: float, what: str) -> float:
    if not (isinstance(x, (int, float)) and math.isfinite(x) and x > 0):
        raise TrajectoryError(f"{what} must be a positive number, got {x!r}")
    return float(x)


def _hold(q: Sequence[float], time: float) -> list[TrajectoryPoint]:
    return [TrajectoryPoint([float(v) for v in q], [0.0] * len(q), time)]


# ---- joint moves --------------------------------------------------------------------------------------------
def joint_move(start_q: Sequence[float], target_q: Sequence[float], speed: float, acceleration: float,
               velocity_limits: Optional[Sequence[float]] = None, *,
               sample_time: float = SAMPLE_TIME) -> list[TrajectoryPoint]:
    """A straight line in joint space (like moveJ), one trapezoid for all joints so they all arrive together.

    speed (rad/s) and acceleration (rad/s^2) apply to every joint, speed also capped per joint by
    velocity_limits; the joint with the farthest way to go relative to its limits sets the pace, the others
    follow proportionally. The last point is exactly target_q with velocity 0. No move (already there): one
    point, the target, after sample_time.
    """
    q0 = _vector(start_q, None, "start joints")
    q1 = _vector(target_q, len(q0), "target joints")
    speed = _positive(speed, "speed")
    acceleration = _positive(acceleration, "acceleration")
    sample_time = _positive(sample_time, "sample time")
    vmax = np.full(len(q0), speed)
    if velocity_limits is not None:
        vl = np.asarray(velocity_limits, dtype=float)
        if vl.shape != q0.shape or np.any(np.isnan(vl)) or np.any(vl <= 0):
            raise TrajectoryError(f"velocity limits: expected {len(q0)} positive numbers, got {list(velocity_limits)!r}")
        vmax = np.minimum(vmax, vl)
    d = q1 - q0
    moving = np.abs(d) > 1e-12
    if not np.any(moving):
        return _hold(q1, sample_time)
    # The path parameter s runs 0..1; joint i moves d_i * s, so s' <= v_i / |d_i| and s'' <= a / |d_i|.
    s_speed = float(np.min(vmax[moving] / np.abs(d[moving])))
    s_acc = float(np.min(acceleration / np.abs(d[moving])))
    prof = Trapezoid.plan(1.0, s_speed, s_acc)
    points = []
    for t in prof.sample_times(sample_time):
        s, sd = prof.at(t)
        points.append(TrajectoryPoint([float(v) for v in q0 + d * s], [float(v) for v in d * sd], t))
    last = points[-1]
    points[-1] = TrajectoryPoint([float(v) for v in q1], [0.0] * len(q1), last.time_from_start)
    return points


# ---- linear moves -------------------------------------------------------------------------------------------
def _mm(x: float) -> str:
    return f"{x * 1000:.0f} mm"


def _pose_text(pose: Sequence[float]) -> str:
    return "(" + ", ".join(f"{v * 1000:.1f}" for v in pose[:3]) + ") mm"


class LinearPath(NamedTuple):
    """The joints of a straight TCP line, one row per waypoint (the first row the start, the last the target)."""
    qs: np.ndarray
    length: float                   # m the TCP travels
    angle: float                    # rad the tool turns


def linear_path(kin: Kinematics, start_q: Sequence[float], target_pose: Sequence[float], *,
                max_step: float = MAX_STEP, max_step_angle: float = MAX_STEP_ANGLE,
                max_joint_step: float = MAX_JOINT_STEP) -> LinearPath:
    """The waypoints of a straight TCP line (like moveL) from FK(start_q) to target_pose: position along the line,
    orientation by slerp, every <= max_step / max_step_angle, each solved by IK seeded with the previous one (so
    the arm stays in its configuration). Its last row is where linear_move ends: the move's target joints.
    No motion (already there): the start alone.

    Raises TrajectoryError: "pose unreachable: ...", "joint limit: ...", "singularity: ...".
    """
    q0 = _vector(start_q, kin.n, "start joints")
    target = _vector(target_pose, 6, "target pose")
    start_t = frames.pose_to_matrix(kin.fk(q0))
    target_t = frames.pose_to_matrix(target)
    dp = target_t[:3, 3] - start_t[:3, 3]
    length = float(np.linalg.norm(dp))
    rel = frames.matrix_to_rotvec(target_t[:3, :3] @ start_t[:3, :3].T)   # start -> target, base axes
    angle = float(np.linalg.norm(rel))
    if length < 1e-7 and angle < 1e-7:
        return LinearPath(np.array([q0]), length, angle)
    # Cheap refusal first: is the target reachable at all (any configuration within the limits)?
    if kin.ik(target, q0) is None:
        raise TrajectoryError(f"pose unreachable: no joint solution within the joint limits reaches the target "
                              f"{_pose_text(target)}")

    n = max(1, math.ceil(length / max_step - 1e-9), math.ceil(angle / max_step_angle - 1e-9))
    qs = [q0]
    prev = list(q0)
    for k in range(1, n + 1):
        s = k / n
        pose_t = np.eye(4)
        pose_t[:3, 3] = start_t[:3, 3] + s * dp
        pose_t[:3, :3] = frames.rotvec_to_matrix(rel * s) @ start_t[:3, :3]
        pose = target if k == n else frames.matrix_to_pose(pose_t)
        where = f"{_mm(s * length)} along the line" if length >= 1e-4 else f"{math.degrees(s * angle):.0f} deg into the turn"
        q = kin.ik(pose, prev, within_limits=False, restarts=False)      # the continuation of the arm's pose
        if q is not None and kin.limit_violation(q, 1e-9) is not None:
            j = kin.limit_violation(q, 1e-9)
            alt = kin.ik(pose, prev)                                       # another within the limits, close by?
            if alt is None or max(abs(a - b) for a, b in zip(alt, prev)) > max_joint_step:
                bound = kin.upper[j] if q[j] > kin.upper[j] else kin.lower[j]
                raise TrajectoryError(f"joint limit: {kin.joint_names[j]} would pass its limit "
                                      f"({math.degrees(bound):.1f} deg) {where}; use a joint move or another "
                                      "start configuration")
            q = alt
        if q is None:
            q = kin.ik(pose, prev)
            if q is None:
                raise TrajectoryError(f"pose unreachable: the line leaves the arm's reach {where} "
                                      f"(at {_pose_text(pose)})")
        steps = [abs(a - b) for a, b in zip(q, prev)]
        j = int(np.argmax(steps))
        if steps[j] > max_joint_step:
            raise TrajectoryError(f"singularity: {kin.joint_names[j]} would turn {math.degrees(steps[j]):.0f} deg "
                                  f"within {_mm(length / n)} {where}; the line passes near a singularity or needs "
                                  "a configuration change; use a joint move")
        qs.append(np.asarray(q, dtype=float))
        prev = q
    return LinearPath(np.array(qs), length, angle)


def linear_move(kin: Kinematics, start_q: Sequence[float], target_pose: Sequence[float], tcp_speed: float,
                tcp_acceleration: float, max_joint_speed: float, *, rotation_speed: Optional[float] = None,
                rotation_acceleration: Optional[float] = None, max_joint_acceleration: Optional[float] = None,
                max_step: float = MAX_STEP, max_step_angle: float = MAX_STEP_ANGLE,
                max_joint_step: float = MAX_JOINT_STEP) -> list[TrajectoryPoint]:
    """A straight TCP line (like moveL) from FK(start_q) to target_pose: the waypoints of linear_path, both
    position and orientation on one trapezoidal timing law.

    Speeds: the TCP at most tcp_speed (m/s) and tcp_acceleration; the tool's turning at most rotation_speed
    (rad/s, default max_joint_speed) and rotation_acceleration (default: the same ramp time as the TCP's);
    no joint above max_joint_speed (nor its URDF velocity limit) and, when given, max_joint_acceleration
    (accounted for along the path, not for the path's curvature in joint space). The timing is stretched until
    the finished points, checked with kin.tcp_speed, keep every cap.

    Raises TrajectoryError: "pose unreachable: ...", "joint limit: ...", "singularity: ...".
    """
    q0 = _vector(start_q, kin.n, "start joints")
    _vector(target_pose, 6, "target pose")
    tcp_speed = _positive(tcp_speed, "TCP speed")
    tcp_acceleration = _positive(tcp_acceleration, "TCP acceleration")
    max_joint_speed = _positive(max_joint_speed, "joint speed")
    rot_speed = _positive(rotation_speed, "rotation speed") if rotation_speed is not None else max_joint_speed
    rot_acc = _positive(rotation_acceleration, "rotation acceleration") if rotation_acceleration is not None \
        else rot_speed * tcp_acceleration / tcp_speed

    path = linear_path(kin, q0, target_pose, max_step=max_step, max_step_angle=max_step_angle,
                       max_joint_step=max_joint_step)
    if len(path.qs) == 1:
        return _hold(q0, SAMPLE_TIME)
    return _time_path(kin, path.qs, path.length, path.angle, tcp_speed, tcp_acceleration, rot_speed, rot_acc,
                      max_joint_speed, max_joint_acceleration)


def _time_path(kin: Kinematics, qs: np.ndarray, length: float, angle: float, tcp_speed: float, tcp_acc: float,
               rot_speed: float, rot_acc: float, max_joint_speed: float,
               max_joint_acc: Optional[float]) -> list[TrajectoryPoint]:
    """One trapezoid on the path parameter s (0..1, waypoints equally spaced), slowed until every point (and the
    cubic between points, at its middle) keeps the TCP, rotation and joint speed caps."""
    n = len(qs) - 1
    h = 1.0 / n
    # dq/ds: central differences inside, the chords at the ends; the bound also takes the chords (the cubic
    # between two points moves the joint at least that fast on average).
    dqds = np.empty_like(qs)
    dqds[1:-1] = (qs[2:] - qs[:-2]) / (2 * h)
    dqds[0] = (qs[1] - qs[0]) / h
    dqds[-1] = (qs[-1] - qs[-2]) / h
    chords = np.abs(np.diff(qs, axis=0)) / h
    jlim = np.minimum(max_joint_speed, np.asarray(kin.velocity_limits, dtype=float))
    per_joint = np.maximum(np.max(np.abs(dqds), axis=0), np.max(chords, axis=0))
    s_speed = min([tcp_speed / length] if length > 1e-9 else [math.inf])
    s_speed = min(s_speed, rot_speed / angle if angle > 1e-9 else math.inf)
    s_acc = min(tcp_acc / length if length > 1e-9 else math.inf, rot_acc / angle if angle > 1e-9 else math.inf)
    moving = per_joint > 1e-12
    if np.any(moving):
        s_speed = min(s_speed, float(np.min(jlim[moving] / per_joint[moving])))
        if max_joint_acc is not None:
            s_acc = min(s_acc, float(max_joint_acc / np.max(per_joint[moving])))
    for _ in range(_TIMING_PASSES):
        prof = Trapezoid.plan(1.0, s_speed, s_acc)
        times = [prof.time_at(k * h) for k in range(n + 1)]
        times[-1] = prof.duration
        sd = np.array([prof.at(t)[1] for t in times])
        qd = dqds * sd[:, None]
        qd[-1] = 0.0
        worst = _worst_ratio(kin, qs, qd, times, tcp_speed, jlim)
        if worst <= 1.0:
            break
        s_speed /= worst * 1.001
    else:
        raise TrajectoryError("the linear move cannot be timed within the speed limits")
    return [TrajectoryPoint([float(v) for v in qs[k]], [float(v) for v in qd[k]], float(times[k]))
            for k in range(1, n + 1)]


def _worst_ratio(kin: Kinematics, qs: np.ndarray, qd: np.ndarray, times: Sequence[float], tcp_speed: float,
                 jlim: np.ndarray) -> float:
    """The largest (measured / allowed) of the TCP speed and the joint speeds, at the points and at quarters of
    the cubic between each pair (what the controller interpolates)."""
    worst = 0.0
    for k in range(len(qs)):
        worst = max(worst, kin.tcp_speed(qs[k], qd[k]) / tcp_speed, float(np.max(np.abs(qd[k]) / jlim)))
        if k + 1 < len(qs):
            for tau in _CHECK_TAUS:
                q, v = _hermite(qs[k], qd[k], qs[k + 1], qd[k + 1], times[k + 1] - times[k], tau)
                worst = max(worst, kin.tcp_speed(q, v) / tcp_speed, float(np.max(np.abs(v) / jlim)))
    return worst


def _hermite(p0: np.ndarray, v0: np.ndarray, p1: np.ndarray, v1: np.ndarray, dt: float,
             tau: float) -> tuple[np.ndarray, np.ndarray]:
    """Position and velocity of the cubic through (p0, v0) and (p1, v1), dt apart, at the fraction tau."""
    t2, t3 = tau * tau, tau * tau * tau
    pos = (2 * t3 - 3 * t2 + 1) * p0 + (t3 - 2 * t2 + tau) * dt * v0 + (3 * t2 - 2 * t3) * p1 + (t3 - t2) * dt * v1
    vel = (6 * t2 - 6 * tau) * (p0 - p1) / dt + (3 * t2 - 4 * tau + 1) * v0 + (3 * t2 - 2 * tau) * v1
    return pos, vel


# ---- jogging ------------------------------------------------------------------------------------------------
def jog_point(q: Sequence[float], qd: Sequence[float], horizon: float, *,
              lower: Optional[Sequence[float]] = None, upper: Optional[Sequence[float]] = None) -> TrajectoryPoint:
    """The next point of a streamed jog: where the joints are `horizon` seconds ahead at velocities qd, moving on.
    With limits given, a joint that would pass one stops at it (position clamped, velocity 0)."""
    horizon = _positive(horizon, "horizon")
    q0 = _vector(q, None, "joints")
    v = _vector(qd, len(q0), "joint velocities")
    pos = q0 + v * horizon
    if lower is not None or upper is not None:
        lo = np.asarray(lower if lower is not None else [-math.inf] * len(q0), dtype=float)
        hi = np.asarray(upper if upper is not None else [math.inf] * len(q0), dtype=float)
        clamped = np.clip(pos, lo, hi)
        v = np.where(clamped != pos, 0.0, v)
        pos = clamped
    return TrajectoryPoint([float(x) for x in pos], [float(x) for x in v], horizon)


def jog_joint_velocities(kin: Kinematics, q: Sequence[float], twist: Sequence[float], max_joint_speed: float, *,
                         max_tcp_speed: float = TCP_SPEED_CAP * TCP_COMMAND_MARGIN) -> list[float]:
    """Joint velocities for a Cartesian jog twist (base axes, about the TCP: vx, vy, vz, wx, wy, wz).

    The whole vector is scaled down (the direction kept) until no joint is above max_joint_speed (nor its URDF
    velocity limit) and the TCP is not faster than the twist's own linear speed (when it has one) and
    max_tcp_speed, checked with the Jacobian at q. Near a singularity the damped least squares slows the
    motion rather than racing a joint.
    """
    max_joint_speed = _positive(max_joint_speed, "joint speed")
    tw = _vector(twist, 6, "twist")
    qd = np.asarray(kin.twist_to_joint_velocities(q, tw), dtype=float)
    scale = 1.0
    jlim = np.minimum(max_joint_speed, np.asarray(kin.velocity_limits, dtype=float))
    over = float(np.max(np.abs(qd) / jlim)) if len(qd) else 0.0
    if over > 1.0:
        scale = 1.0 / over
    cap = max_tcp_speed
    lin = float(np.linalg.norm(tw[:3]))
    if lin > 0:
        cap = min(cap, lin)
    speed = kin.tcp_speed(q, qd) * scale
    if speed > cap:
        scale *= cap / speed
    return [float(v) for v in qd * scale]
