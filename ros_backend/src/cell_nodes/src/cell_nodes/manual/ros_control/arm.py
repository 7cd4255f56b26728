"""One ros_control arm as the driver core sees a controller: the same small protocol as ur_rtde's interfaces
(controller.py: ReceiveInterface, ControlInterface, IOInterface, DashboardInterface), carried out through the
standard interfaces of the arm's own ROS driver (a Transport: joint states, the FollowJointTrajectory action, the
trajectory controller's command topic, SetBool/Bool IO, the URDF). No ROS here; transport.py is the rospy side.

Why this seam: every motion-safety rule (hold-to-run, the heartbeat watchdog, never queued, Stop without the lease,
the TCP cap, the arrival checks) lives once in driver.ManualDriver; a backend only says how to read and move its arm.

How it moves:
- moves (moveJ, moveL) are FollowJointTrajectory goals built by trajectory.py from the URDF's kinematics (a
  straight TCP line for moveL, IK at every waypoint); the goal carries a path tolerance, so a blocked arm aborts;
- jogs (speedJ, speedL) are streamed on the controller's command topic: every STREAM_PERIOD one point
  JOG_HORIZON ahead, as moveit_servo / jog_arm do for ROS 1. Why not a velocity group controller: it would need a
  controller switch (controller_manager) before and after every jog, and it keeps the last velocity for ever if our
  node dies; a streamed trajectory ends by itself JOG_HORIZON after the last point (a dead-man in the controller);
- stop cancels the goal, ends the stream and sends an empty trajectory (the controller holds where it is).
"""
from __future__ import annotations

import math
import threading
import time
from dataclasses import dataclass
from typing import Callable, Optional, Protocol, Sequence

from ..config import RosControlSpec
from ..controller import CONTROLLER_NOT_RUNNING, RUNTIME_PLAYING
from ...said import Said, say
from ..driver import Refused
from . import trajectory
from .kinematics import Kinematics, KinematicsError

STREAM_PERIOD = 0.01        # s between streamed jog points
JOG_HORIZON = 0.2           # s: each streamed point lies this far ahead; the arm stops this long after the last one
STATE_TIMEOUT = 2.0         # s to wait for the first joint state at connect
LIMIT_MARGIN = 0.01         # rad a jog keeps from a joint limit
# Streamed jogs run this much under the commanded speed: message timing between our node and the controller (a few
# ms on a 10 ms period on a busy PC) lets the controller's setpoint run up to ~4 % fast for a moment (measured:
# 254 mm/s for 245 commanded), and the 250 mm/s cap is on the actual TCP speed.
STREAM_SPEED_FACTOR = 0.95
ROBOT_RUNNING, SAFETY_NORMAL, RUNTIME_STOPPED = 7, 1, 1

# control_msgs/FollowJointTrajectoryResult error codes (their names, for the user's message)
ERROR_CODES = {0: "SUCCESSFUL", -1: "INVALID_GOAL", -2: "INVALID_JOINTS", -3: "OLD_HEADER_TIMESTAMP",
               -4: "PATH_TOLERANCE_VIOLATED", -5: "GOAL_TOLERANCE_VIOLATED"}
# actionlib goal states
PENDING, ACTIVE, PREEMPTED, SUCCEEDED, ABORTED, REJECTED, PREEMPTING, RECALLING, RECALLED, LOST = range(10)


class Unreachable(RuntimeError):
    """The arm cannot be driven now; `reason` says why in the user's words (the driver adds it to its message)."""

    def __init__(self, reason: str) -> None:
        super().__init__(reason)
        self.reason = reason


@dataclass(frozen=True)
class JointSample:
    """One sensor_msgs/JointState, as received."""
    names: tuple[str, ...]
    position: tuple[float, ...]
    velocity: tuple[float, ...]
    received: float                 # our monotonic clock when it arrived


class Transport(Protocol):
    """The arm's own ROS driver, as the backend uses it (transport.RosTransport; fakes in the tests)."""

    def joint_state(self) -> Optional[JointSample]: ...
    def controller_ready(self) -> bool: ...
    def send_goal(self, names: Sequence[str], points: Sequence[trajectory.TrajectoryPoint], path_tolerance: float,
                  goal_time_tolerance: float, done: Callable[[int, int, str], None]) -> None: ...
    def cancel_goal(self) -> None: ...
    def stream(self, names: Sequence[str], point: trajectory.TrajectoryPoint) -> None: ...
    def hold(self) -> None: ...
    def set_output(self, output: int, value: bool) -> None: ...
    def inputs(self) -> dict[int, bool]: ...
    def robot_description(self) -> str: ...
    def close(self) -> None: ...


def load_kinematics(spec: RosControlSpec, joints: Sequence[str], urdf: str) -> Kinematics:
    """The arm's kinematics from its URDF; Unreachable (naming the field) when it does not load or does not fit."""
    try:
        kin = Kinematics.from_urdf(urdf, spec.base_link, spec.tip_link)
    except KinematicsError as e:
        raise Unreachable(f"the URDF ({spec.robot_description or spec.urdf}) does not give the arm's kinematics: {e}")
    if sorted(kin.joint_names) != sorted(joints):
        raise Unreachable(f"manual joints {', '.join(joints)} are not the URDF's joints from {spec.base_link} to "
                          f"{spec.tip_link} ({', '.join(kin.joint_names)})")
    return kin


class RosControlArm:
    """Receive, control, IO and dashboard interface of one ros_control arm (the driver core holds one lock around
    every call: see controller.Gate). Joint vectors are in the group's joint order."""

    def __init__(self, spec: RosControlSpec, joints: Sequence[str], transport: Transport, kin: Kinematics,
                 max_joint_speed: float, clock: Callable[[], float] = time.monotonic,
                 stale_s: float = 1.0) -> None:
        self.spec = spec
        self.joints = tuple(joints)
        self.transport = transport
        self.kin = kin
        self.max_joint_speed = max_joint_speed
        self.clock = clock
        self.stale_s = stale_s
        # The kinematics' joint order may differ from the group's: map once.
        self._to_kin = [self.joints.index(n) for n in kin.joint_names]
        self._lock = threading.Lock()
        self._goal_seq = 0
        self._goal_active = False
        self._move_error = ""
        self._outputs = 0
        self._closed = False
        self._stream: Optional[_JogStream] = None

    # ------------------------------------------------------------------ reading
    def sample(self) -> JointSample:
        s = self.transport.joint_state()
        if s is None:
            raise Unreachable(f"no joint states on {self.spec.joint_states}")
        missing = [j for j in self.joints if j not in s.names]
        if missing:
            raise Unreachable(f"{self.spec.joint_states} does not carry joint {missing[0]} (it has: "
                              f"{', '.join(s.names) or 'none'}): check manual.groups[].joints")
        return s

    def _q_qd(self) -> tuple[list[float], list[float]]:
        s = self.sample()
        index = {n: i for i, n in enumerate(s.names)}
        q = [s.position[index[j]] for j in self.joints]
        qd = [s.velocity[index[j]] if len(s.velocity) == len(s.names) else 0.0 for j in self.joints]
        return q, qd

    def _kin_q(self, q: Sequence[float]) -> list[float]:
        return [q[i] for i in self._to_kin]

    def _from_kin(self, qk: Sequence[float]) -> list[float]:
        out = [0.0] * len(self.joints)
        for k, i in enumerate(self._to_kin):
            out[i] = qk[k]
        return out

    def isConnected(self) -> bool:
        if self._closed:
            return False
        s = self.transport.joint_state()
        return s is not None and self.clock() - s.received < self.stale_s

    def getTimestamp(self) -> float:
        s = self.transport.joint_state()
        return s.received if s is not None else 0.0

    def getActualQ(self) -> list[float]:
        return self._q_qd()[0]

    def getActualQd(self) -> list[float]:
        return self._q_qd()[1]

    def getActualTCPPose(self) -> list[float]:
        return self.kin.fk(self._kin_q(self._q_qd()[0]))

    def getActualTCPSpeed(self) -> list[float]:
        q, qd = self._q_qd()
        return list(self.kin.tcp_velocity(self._kin_q(q), self._kin_q(qd)))

    def getRobotMode(self) -> int:
        return ROBOT_RUNNING if self.transport.controller_ready() else CONTROLLER_NOT_RUNNING

    def getSafetyMode(self) -> int:
        return SAFETY_NORMAL  # ROS has no standard safety state; a vendor driver's would be read here

    def getSpeedScaling(self) -> float:
        return 1.0

    def getRuntimeState(self) -> int:
        return RUNTIME_PLAYING if self.transport.controller_ready() else RUNTIME_STOPPED

    def getActualDigitalInputBits(self) -> int:
        return sum(1 << n for n, v in self.transport.inputs().items() if v)

    def getActualDigitalOutputBits(self) -> int:
        return self._outputs

    # ------------------------------------------------------------------ the control "script"
    def isProgramRunning(self) -> bool:
        return self.transport.controller_ready()

    def reuploadScript(self) -> bool:
        return self.transport.controller_ready()

    def stopScript(self) -> None:
        self._halt()

    def disconnect(self) -> None:
        self._end_stream()

    def close(self) -> None:
        self._closed = True
        self._end_stream()
        self.transport.close()

    # ------------------------------------------------------------------ kinematics
    def getForwardKinematics(self, q: list[float], tcp_offset: Optional[list[float]] = None) -> list[float]:
        return self.kin.fk(self._kin_q(q))

    def getInverseKinematicsHasSolution(self, pose: list[float], qnear: list[float], max_position_error: float = 0.0,
                                        max_orientation_error: float = 0.0) -> bool:
        return self.kin.ik(pose, self._kin_q(qnear)) is not None

    def getTCPOffset(self) -> list[float]:
        return [0.0] * 6  # the URDF's tip link is the TCP

    # What the driver core asks for a move's target (driver.ManualDriver.move_target) where ur_rtde's controller
    # answers with getInverseKinematics and isJointsWithinSafetyLimits: here the answers of this backend's own moves.
    def getLinearMoveTarget(self, pose: list[float], qnear: list[float]) -> list[float]:
        """The joints a moveL from `qnear` to `pose` ends at: the last waypoint of the line moveL itself follows
        (trajectory.linear_path, IK seeded waypoint by waypoint). Refused with moveL's own words when the line
        cannot be followed (a joint limit, a singularity, out of reach on the way)."""
        try:
            path = trajectory.linear_path(self.kin, self._kin_q(qnear), list(pose))
        except trajectory.TrajectoryError as e:
            raise Refused(str(e))
        return self._from_kin([float(v) for v in path.qs[-1]])

    def getJointLimitError(self, q: list[float]) -> Said:
        """Why moveJ would refuse the joint target `q` (the URDF's position limits), "" when it would not."""
        if len(q) != len(self.joints):
            return say("manual.joint_target_count", "a joint target needs {needed} values, got {count}",
                       needed=len(self.joints), count=len(q))
        qk = self._kin_q(q)
        for name, v, lo, hi in zip(self.kin.joint_names, qk, self.kin.lower, self.kin.upper):
            if not lo - 1e-9 <= v <= hi + 1e-9:
                return say("manual.joint_outside_limits", "joint {joint}: target {target} rad is outside its limits "
                           "[{lower}, {upper}] rad", joint=name, target=f"{v:.3f}", lower=f"{lo:.3f}", upper=f"{hi:.3f}")
        return Said("")

    # ------------------------------------------------------------------ moves
    def _check_limits(self, target: Sequence[float]) -> None:
        why = self.getJointLimitError(list(target))
        if why:
            raise Refused(why)

    def moveJ(self, q: list[float], speed: float, acceleration: float, asynchronous: bool = True) -> bool:
        self._check_limits(q)
        start = self._q_qd()[0]
        vmax = [min(speed, v) for v in self._from_kin(self.kin.velocity_limits)]
        points = trajectory.joint_move(start, list(q), speed, acceleration, vmax)
        return self._send(points)

    def moveL(self, pose: list[float], speed: float, acceleration: float, asynchronous: bool = True) -> bool:
        start = self._kin_q(self._q_qd()[0])
        try:
            points = trajectory.linear_move(self.kin, start, list(pose), speed, acceleration, self.max_joint_speed)
        except trajectory.TrajectoryError as e:
            raise Refused(str(e))
        return self._send([trajectory.TrajectoryPoint(self._from_kin(p.positions), self._from_kin(p.velocities),
                                                      p.time_from_start)
                           for p in points])

    def _send(self, points: Sequence[trajectory.TrajectoryPoint]) -> bool:
        if not self.transport.controller_ready():
            raise Refused(say("manual.trajectory_controller_down", "the trajectory controller {controller} is not "
                              "running", controller=self.spec.controller))
        self._end_stream()
        with self._lock:
            self._goal_seq += 1
            seq = self._goal_seq
            self._goal_active, self._move_error = True, ""

        def done(state: int, code: int, text: str) -> None:
            with self._lock:
                if seq != self._goal_seq:
                    return  # an older goal's late result
                self._goal_active = False
                if state == SUCCEEDED:
                    return
                if state in (ABORTED, REJECTED) or code != 0:
                    what = "rejected" if state == REJECTED else "aborted"
                    self._move_error = (f"the controller {what} the trajectory: "
                                        f"{ERROR_CODES.get(code, str(code))}" + (f" ({text})" if text else ""))
                elif state == LOST:
                    self._move_error = "the trajectory controller stopped answering during the move"
                elif state in (PREEMPTED, RECALLED):
                    # Not ours: our own stop or next goal moved _goal_seq on before cancelling.
                    self._move_error = "the trajectory was preempted: another client commanded the arm's controller"

        self.transport.send_goal(self.joints, points, self.spec.path_tolerance, self.spec.goal_time_tolerance, done)
        return True

    def getAsyncOperationProgress(self) -> int:
        return 0 if self._goal_active else -1

    def getMoveError(self) -> str:
        return self._move_error

    # ------------------------------------------------------------------ jogs
    def speedJ(self, qd: list[float], acceleration: float, time_s: float = 0.0) -> bool:
        velocities = list(qd)
        top = max((abs(v) for v in velocities), default=0.0)
        return self._jog(lambda q, f: [v * f * STREAM_SPEED_FACTOR for v in velocities],
                         acceleration / top if top > 0 else math.inf)

    def speedL(self, xd: list[float], acceleration: float, time_s: float = 0.0) -> bool:
        twist = list(xd)
        top = math.hypot(*twist[:3]) or math.hypot(*twist[3:])

        def velocities(q: list[float], f: float) -> list[float]:
            return self._from_kin(trajectory.jog_joint_velocities(
                self.kin, self._kin_q(q), [v * f * STREAM_SPEED_FACTOR for v in twist], self.max_joint_speed))
        return self._jog(velocities, acceleration / top if top > 0 else math.inf)

    def _jog(self, velocities: Callable[[list[float], float], list[float]], ramp: float) -> bool:
        """Stream `velocities(q, f)` with f rising from 0 to 1 at `ramp` per second (the command's acceleration):
        a jog that jumped to full speed would make the controller's spline overshoot it (measured: the TCP at
        1.2x the commanded speed), and the 250 mm/s cap is on the actual speed."""
        if not self.transport.controller_ready():
            raise Refused(say("manual.trajectory_controller_down", "the trajectory controller {controller} is not "
                              "running", controller=self.spec.controller))
        with self._lock:
            if self._goal_active:
                self._goal_seq += 1  # its PREEMPTED result is ours, not a fault
                self.transport.cancel_goal()
                self._goal_active = False
            stream = self._stream
        if stream is not None and stream.alive():
            stream.replace(velocities, ramp)  # a new speed replaces the running one (no second stream)
            return True
        lower, upper = self._from_kin(self.kin.lower), self._from_kin(self.kin.upper)
        self._stream = _JogStream(self.joints, self._q_qd()[0], velocities, ramp, self.transport, lower, upper,
                                  self.clock)
        return True

    def _end_stream(self) -> None:
        stream, self._stream = self._stream, None
        if stream is not None:
            stream.end()

    def _halt(self) -> None:
        """Stop whatever we commanded (and what another client did): end the stream, cancel, hold."""
        self._end_stream()
        with self._lock:
            self._goal_seq += 1  # a result arriving now is ours being cancelled: not a fault
            self._goal_active = False
        self.transport.cancel_goal()
        self.transport.hold()

    def speedStop(self, a: float = 10.0) -> bool:
        self._halt()
        return True

    def stopJ(self, a: float = 2.0, asynchronous: bool = False) -> None:
        self._halt()

    def stopL(self, a: float = 10.0, asynchronous: bool = False) -> None:
        self._halt()

    # ------------------------------------------------------------------ IO
    def setStandardDigitalOut(self, output_id: int, signal_level: bool) -> bool:
        if output_id not in self.spec.outputs:
            raise Refused(say("manual.output_not_wired", "digital output {output} is not wired "
                              "(manual.groups[].ros_control.io.outputs)", output=output_id))
        self.transport.set_output(output_id, bool(signal_level))
        with self._lock:
            self._outputs = (self._outputs | 1 << output_id) if signal_level else (self._outputs & ~(1 << output_id))
        return True

    # ------------------------------------------------------------------ dashboard (the app's Stop of a foreign move)
    def connect(self, timeout_ms: int = 2000) -> None:
        pass

    def stop(self) -> None:
        self._halt()


class _JogStream:
    """Streams jog points on its own thread until ended, never past a joint limit.

    Each point lies JOG_HORIZON ahead of where the controller's setpoint is now, at the commanded velocity. The
    controller splines (cubic) from its current setpoint to the point; that setpoint is not published, so the stream
    follows the spline it sent itself (sampled at the time since): basing each point on a position integrated apart
    from it let the setpoint lag during the speed ramp and then catch up faster than commanded (measured: the TCP
    at 1.1x the commanded speed at the end of the ramp)."""

    def __init__(self, joints: Sequence[str], q0: Sequence[float],
                 velocities: Callable[[list[float], float], list[float]], ramp: float, transport: Transport,
                 lower: Sequence[float], upper: Sequence[float], clock: Callable[[], float]) -> None:
        self.joints = tuple(joints)
        self.q = list(q0)           # the controller's setpoint now (as the stream models it)
        self.v = [0.0] * len(self.q)
        self._sent: Optional[tuple[list[float], list[float], list[float]]] = None  # (q0, v0, v1) of the last spline
        self.velocities = velocities
        self.ramp = ramp
        self.f = 0.0                # the fraction of the commanded speed reached
        self.transport = transport
        self.lower, self.upper = list(lower), list(upper)
        self.clock = clock
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="ros-control-jog", daemon=True)
        self._thread.start()

    def alive(self) -> bool:
        return self._thread.is_alive() and not self._stop.is_set()

    def end(self) -> None:
        self._stop.set()
        if threading.current_thread() is not self._thread:
            self._thread.join(1.0)

    def replace(self, velocities: Callable[[list[float], float], list[float]], ramp: float) -> None:
        self.velocities, self.ramp = velocities, ramp

    def _advance(self, dt: float) -> None:
        """Move the modelled setpoint along the last spline sent (start q0, v0; end q0 + v1 h, v1; h the horizon)."""
        if self._sent is None:
            return
        q0, v0, v1 = self._sent
        if dt >= JOG_HORIZON:  # the spline ended: the controller holds its last point
            self.q, self.v = [a + c * JOG_HORIZON for a, c in zip(q0, v1)], [0.0] * len(q0)
            return
        x = dt / JOG_HORIZON
        self.q = [a + b * JOG_HORIZON * x + (c - b) * JOG_HORIZON * (2 * x * x - x ** 3) for a, b, c in zip(q0, v0, v1)]
        self.v = [b + (c - b) * (4 * x - 3 * x * x) for b, c in zip(v0, v1)]

    def step(self, dt: float) -> trajectory.TrajectoryPoint:
        self._advance(dt)
        self.f = min(1.0, self.f + self.ramp * dt)
        qd = list(self.velocities(list(self.q), self.f))
        for i, v in enumerate(qd):
            if not math.isfinite(v):
                qd[i] = 0.0
            # Never into a joint limit: the joint stops at the margin (the others go on).
            ahead = self.q[i] + qd[i] * JOG_HORIZON
            if ahead > self.upper[i] - LIMIT_MARGIN and qd[i] > 0 or ahead < self.lower[i] + LIMIT_MARGIN and qd[i] < 0:
                qd[i] = 0.0
        self._sent = (list(self.q), list(self.v), qd)
        return trajectory.jog_point(self.q, qd, JOG_HORIZON)

    def _run(self) -> None:
        last = self.clock()
        while not self._stop.is_set():
            now = self.clock()
            point = self.step(now - last)  # the real time since: the model must follow the controller's clock
            last = now
            if self._stop.is_set():
                return  # ended while computing: the stop's hold must be the last word
            self.transport.stream(self.joints, point)
            self._stop.wait(STREAM_PERIOD)
