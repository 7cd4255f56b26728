"""Setpoint generators for the controller's motion commands (moveJ, moveL, stop, speedJ/L, servoJ).

Each generator is advanced once per controller tick and returns the joint setpoint (q, qd); the physics then
tracks that setpoint with joint position control, so motion is executed by the simulated arm.
"""
from __future__ import annotations

import math
from typing import Optional, Protocol

import numpy as np

from . import kinematics as kin

MAX_JOINT_SPEED = 3.14      # rad/s, UR5 joint speed limit
SERVO_MAX_ACC = 15.0        # rad/s^2, servoJ setpoint acceleration limit
ROT_TO_LENGTH = 0.1         # moveL: 1 rad of tool rotation counts as 0.1 m of path (UR blends both the same way)


class MotionError(RuntimeError):
    """The motion cannot continue (e.g. no IK solution on a moveL path); the controller stops the program."""


class Motion(Protocol):
    def step(self, dt: float) -> tuple[np.ndarray, np.ndarray, bool]: ...


class Trapezoid:
    """Time-optimal 1-D profile over length L with speed v and acceleration a (triangular if L is short)."""

    def __init__(self, length: float, v: float, a: float) -> None:
        self.length = max(length, 0.0)
        v, a = max(v, 1e-6), max(a, 1e-6)
        if self.length * a < v * v:  # never reaches cruise speed
            v = math.sqrt(self.length * a)
        self.v, self.a = v, a
        self.t_acc = v / a
        self.t_total = (self.length / v + self.t_acc) if v > 0 else 0.0

    def at(self, t: float) -> tuple[float, float]:
        """Distance travelled and speed at time t."""
        if self.length <= 0 or t >= self.t_total:
            return self.length, 0.0
        if t < self.t_acc:
            return 0.5 * self.a * t * t, self.a * t
        if t < self.t_total - self.t_acc:
            return 0.5 * self.a * self.t_acc ** 2 + self.v * (t - self.t_acc), self.v
        rest = self.t_total - t
        return self.length - 0.5 * self.a * rest * rest, self.a * rest


class JointMove:
    """moveJ: straight line in joint space; the leading joint moves with the given speed and acceleration."""

    def __init__(self, q_start: np.ndarray, q_goal: np.ndarray, v: float, a: float) -> None:
        self.q0 = np.asarray(q_start, dtype=float)
        self.delta = np.asarray(q_goal, dtype=float) - self.q0
        self.goal = self.q0 + self.delta
        lead = float(np.max(np.abs(self.delta)))
        self.profile = Trapezoid(lead, min(v, MAX_JOINT_SPEED), a)
        self.unit = self.delta / lead if lead > 0 else np.zeros(6)
        self.t = 0.0

    def step(self, dt: float) -> tuple[np.ndarray, np.ndarray, bool]:
        self.t += dt
        s, sd = self.profile.at(self.t)
        return self.q0 + self.unit * s, self.unit * sd, self.t >= self.profile.t_total


class LinearMove:
    """moveL: the TCP follows a straight line (orientation slerped); IK from the previous setpoint each tick."""

    def __init__(self, q_start: np.ndarray, pose_goal: np.ndarray, v: float, a: float, tcp: np.ndarray) -> None:
        self.tcp = np.asarray(tcp, dtype=float)
        self.start = kin.fk_frames(q_start)[6] @ kin.pose_to_matrix(self.tcp)
        self.end = kin.pose_to_matrix(pose_goal)
        dist = float(np.linalg.norm(self.end[:3, 3] - self.start[:3, 3]))
        angle = float(np.linalg.norm(kin.matrix_to_rotvec(self.end[:3, :3] @ self.start[:3, :3].T)))
        self.length = max(dist, angle * ROT_TO_LENGTH)
        self.profile = Trapezoid(self.length, v, a)
        self.q = np.asarray(q_start, dtype=float)
        self.t = 0.0
        # Fail before moving if the goal has no solution near the path end (real controllers refuse too).
        if kin.inverse(kin.matrix_to_pose(self.end), self.q, self.tcp) is None:
            raise MotionError("moveL: no inverse kinematics solution for the target pose")

    def step(self, dt: float) -> tuple[np.ndarray, np.ndarray, bool]:
        self.t += dt
        s, _ = self.profile.at(self.t)
        frac = s / self.length if self.length > 0 else 1.0
        target = kin.interpolate_pose(self.start, self.end, frac)
        q = kin.inverse(kin.matrix_to_pose(target), self.q, self.tcp, 1e-9, 1e-9, iterations=30)
        if q is None:
            raise MotionError("moveL: inverse kinematics failed along the path")
        qd = (q - self.q) / dt
        if np.max(np.abs(qd)) > MAX_JOINT_SPEED * 1.5:
            raise MotionError("moveL: joint speed limit exceeded (path passes near a singularity)")
        self.q = q
        return q, qd, self.t >= self.profile.t_total


class Stop:
    """stopJ/stopL and protective stops: decelerate the current setpoint velocity to zero."""

    def __init__(self, q: np.ndarray, qd: np.ndarray, decel: float, tcp_speed: Optional[float] = None) -> None:
        self.q0 = np.asarray(q, dtype=float)
        self.v0 = np.asarray(qd, dtype=float)
        lead = tcp_speed if tcp_speed is not None else float(np.max(np.abs(self.v0)))
        self.t_stop = lead / max(decel, 1e-6)
        self.t = 0.0

    def step(self, dt: float) -> tuple[np.ndarray, np.ndarray, bool]:
        self.t = min(self.t + dt, self.t_stop)
        if self.t_stop <= 0:
            return self.q0, np.zeros(6), True
        frac = 1 - self.t / self.t_stop
        q = self.q0 + self.v0 * (self.t - 0.5 * self.t * self.t / self.t_stop)
        return q, self.v0 * frac, self.t >= self.t_stop


class SpeedJ:
    """speedJ: ramp joint velocities toward the target with acceleration a; runs until replaced or stopped."""

    def __init__(self, q: np.ndarray, qd: np.ndarray) -> None:
        self.q = np.asarray(q, dtype=float)
        self.v = np.asarray(qd, dtype=float)
        self.target = np.zeros(6)
        self.acc = 1.0

    def set_target(self, qd: np.ndarray, acc: float) -> None:
        self.target = np.clip(np.asarray(qd, dtype=float), -MAX_JOINT_SPEED, MAX_JOINT_SPEED)
        self.acc = max(acc, 1e-6)

    def step(self, dt: float) -> tuple[np.ndarray, np.ndarray, bool]:
        diff = self.target - self.v
        lead = float(np.max(np.abs(diff)))
        max_dv = self.acc * dt
        self.v = self.target.copy() if lead <= max_dv else self.v + diff * (max_dv / lead)
        self.q = self.q + self.v * dt
        return self.q, self.v, False


class SpeedL(SpeedJ):
    """speedL: a TCP twist (base frame) ramped with acceleration a, mapped to joints through the Jacobian."""

    def __init__(self, q: np.ndarray, qd: np.ndarray, tcp: np.ndarray) -> None:
        super().__init__(q, qd)
        self.tcp = tcp
        self.xd = kin.jacobian(q, tcp) @ np.asarray(qd, dtype=float)
        self.target_x = np.zeros(6)

    def set_target(self, xd: np.ndarray, acc: float) -> None:
        self.target_x = np.asarray(xd, dtype=float)
        self.acc = max(acc, 1e-6)

    def step(self, dt: float) -> tuple[np.ndarray, np.ndarray, bool]:
        diff = self.target_x - self.xd
        lead = float(np.max(np.abs(diff)))
        max_dv = self.acc * dt
        self.xd = self.target_x.copy() if lead <= max_dv else self.xd + diff * (max_dv / lead)
        j = kin.jacobian(self.q, self.tcp)
        qd = np.linalg.solve(j.T @ j + 1e-6 * np.eye(6), j.T @ self.xd)
        if np.max(np.abs(qd)) > MAX_JOINT_SPEED:
            raise MotionError("speedL: joint speed limit exceeded")
        self.q = self.q + qd * dt
        return self.q, qd, False


class ServoJ:
    """servoJ: follow streamed joint targets; the setpoint reaches each target within the servo time."""

    def __init__(self, q: np.ndarray) -> None:
        self.q = np.asarray(q, dtype=float)
        self.target = self.q.copy()
        self.time = 0.008
        self.qd = np.zeros(6)

    def set_target(self, q: np.ndarray, servo_time: float, lookahead: float) -> None:
        self.target = np.asarray(q, dtype=float)
        self.time = max(servo_time, lookahead * 0.5, 0.002)

    def step(self, dt: float) -> tuple[np.ndarray, np.ndarray, bool]:
        qd = (self.target - self.q) / self.time
        lead = float(np.max(np.abs(qd)))
        if lead > MAX_JOINT_SPEED:
            qd *= MAX_JOINT_SPEED / lead
        # A real arm cannot jump in speed: limit acceleration so streamed steps do not jerk the wrist.
        qd = np.clip(qd, self.qd - SERVO_MAX_ACC * dt, self.qd + SERVO_MAX_ACC * dt)
        step = qd * dt
        over = np.abs(step) > np.abs(self.target - self.q)
        step[over] = (self.target - self.q)[over]
        self.q = self.q + step
        self.qd = step / dt
        return self.q, self.qd, False
