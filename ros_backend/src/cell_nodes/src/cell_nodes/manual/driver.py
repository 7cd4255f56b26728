"""The manual-motion driver core: named, relative and absolute moves, hold-to-run jogs, tool actions, stop, the
robot's state, and reconnection, against the abstract controller of controller.py (ur_rtde in the node, a fake in
the unit tests). No ROS here: the node calls these methods from its service, topic and timer callbacks.

Threads and locks:
- every ur_rtde call goes through the Gate (one lock, bounded wait), so one client is never used concurrently;
- `_cmd_lock` orders motion decisions with the commands that carry them out (a jog start can never overtake the
  stop that followed it); only short controller calls are made while holding it (no IK, no connecting, no
  waiting for a move), so the stop service and the jog watchdog never wait long;
- service moves are sent asynchronously (moveJ/moveL asynchronous=True) and the calling thread then polls for
  completion without holding either lock;
- the monitor thread polls the robot state (`poll_rate`) and reconnects every `retry_s` when the controller is
  lost; the watchdog thread stops a jog whose heartbeats stopped.

Targets: every move service (and a tool's move_named step) and the move preview compute where the arm goes with one
function, move_target (validation, the relative target from the current TCP pose, the IK and the joint-limit check
the move relies on), so the 3D view's ghost is exactly what the move then commands.
"""
from __future__ import annotations

import logging
import math
import threading
import time
from dataclasses import dataclass, field, replace
from typing import Callable, Optional, Sequence, TypeVar, cast

from ..said import Said, say
from . import frames
from .config import DigitalOut, Group, ManualConfig, MoveNamedStep, UR_JOINTS, Wait, WaitInput
from .controller import (RUNTIME_PLAYING, STATE_GETTERS, CallTimeout, ClientGone, Connector, ControlInterface, Gate,
                         Guarded, IOInterface, ReceiveInterface, fk_lever, keep_forever, robot_mode_name,
                         run_with_timeout, safety_mode_name)
from .jog import CARTESIAN, FRAMES, JOINT, Decision, Jog, JogSupervisor
from .limits import STOP_DECEL_JOINT, STOP_DECEL_TCP, WATCHDOG_DECEL_JOINT, WATCHDOG_DECEL_TCP, Limits

log = logging.getLogger("cell_nodes.manual")
T = TypeVar("T")

IDLE, JOGGING, MOVING, TOOL, STOPPING = "idle", "jogging", "moving", "tool", "stopping"
STANDSTILL = 0.01           # rad/s: the arm counts as standing still below this on every joint
JOINT_TOLERANCE = 0.005     # rad: a joint move has arrived (the spec asks 0.01)
POSITION_TOLERANCE = 0.001  # m: a linear move has arrived
ANGLE_TOLERANCE = 0.005     # rad
POLL_S = 0.01               # how often a waiting service call looks at the robot
SCRIPT_START_S = 10.0       # from uploading the control script until it runs
STALE_S = 1.0               # RTDE data that stopped changing this long means the controller is gone
MOVABLE_SAFETY = ("NORMAL", "REDUCED")
NAMED, RELATIVE, POSE = "named", "relative", "pose"   # the kinds of move (MoveRequest.kind)
AXES = ("x", "y", "z", "rx", "ry", "rz")


class Refused(Exception):
    """A command the driver does not carry out; the message says why (it goes back to the caller as is), with its
    code when it is a Said (cell_nodes.said)."""

    @property
    def said(self) -> Said:
        text = self.args[0] if self.args else ""
        return text if isinstance(text, Said) else Said(str(text))


class MotionFault(Refused):
    """The controller ended a move itself (an aborted trajectory): reported as the arm's fault until the next
    command, so the alarms feature raises it."""


@dataclass(frozen=True)
class Snapshot:
    """One reading of the robot over RTDE receive."""
    connected: bool = False
    timestamp: float = 0.0                      # controller time, s
    q: tuple[float, ...] = ()                   # rad, UR order
    qd: tuple[float, ...] = ()                  # rad/s
    tcp_pose: tuple[float, ...] = ()            # m, rotation vector
    tcp_speed: tuple[float, ...] = ()           # m/s, rad/s
    robot_mode: str = "NO_CONTROLLER"
    safety_mode: str = "NORMAL"
    speed_scaling: float = 0.0
    program_running: bool = False
    digital_in: int = 0
    digital_out: int = 0

    def standstill(self) -> bool:
        return bool(self.qd) and max(abs(v) for v in self.qd) < STANDSTILL


@dataclass
class DriverState:
    """Everything RobotState carries (the node adds the header)."""
    connected: bool
    controller: str
    robot_mode: str
    safety_mode: str
    speed_scaling: float
    program_running: bool
    motion: str
    motion_group: str
    motion_target: str
    progress: float
    message: str
    joint_positions: list[float] = field(default_factory=list)
    tcp_pose: list[float] = field(default_factory=list)
    tcp_speed: list[float] = field(default_factory=list)
    fault: str = ""                 # the controller ended the last move early (aborted trajectory); "" when none


@dataclass(frozen=True)
class MoveRequest:
    """A move as the services ask for it: move_named, move_relative, move_pose, and preview_move for any of them."""
    kind: str                               # named, relative or pose
    group: str
    name: str = ""                          # named: the configuration
    offset: tuple[float, ...] = ()          # relative: x, y, z (m), rx, ry, rz (rad)
    frame: str = "base"                     # relative: base or tool ("" means base)
    pose: tuple[float, ...] = ()            # pose: x, y, z (m), rx, ry, rz (rad), base frame

    @property
    def label(self) -> str:
        """The state's motion_target while it runs: the configuration, "relative" or "pose"."""
        return self.name if self.kind == NAMED else self.kind


@dataclass(frozen=True)
class MoveTarget:
    """Where a move takes the arm (ManualDriver.move_target): what the move commands, what the preview shows."""
    group: Group
    request: MoveRequest
    start: Snapshot                         # the reading the target was computed from
    q: tuple[float, ...]                    # rad, every joint of the arm: moveJ's target, or where moveL ends
    tcp_pose: tuple[float, ...]             # the TCP there (m, rotation vector, base frame): moveL's target
    linear: bool                            # a straight TCP line (moveL: relative, pose), else a joint move (moveJ)


def read_snapshot(recv: ReceiveInterface) -> Snapshot:
    """All the state one poll needs, in one gate call (one round trip where the client reads them at once)."""
    read_all = getattr(recv, "readState", None)
    values = read_all() if read_all is not None else tuple(getattr(recv, g)() for g in STATE_GETTERS)
    (connected, timestamp, q, qd, tcp_pose, tcp_speed, robot_mode, safety_mode, speed_scaling, runtime_state,
     digital_in, digital_out) = values
    return Snapshot(connected=bool(connected), timestamp=float(timestamp), q=tuple(q), qd=tuple(qd),
                    tcp_pose=tuple(tcp_pose), tcp_speed=tuple(tcp_speed), robot_mode=robot_mode_name(robot_mode),
                    safety_mode=safety_mode_name(safety_mode), speed_scaling=float(speed_scaling),
                    program_running=runtime_state == RUNTIME_PLAYING, digital_in=int(digital_in),
                    digital_out=int(digital_out))


def _finite(values: Sequence[float]) -> bool:
    return all(isinstance(v, (int, float)) and math.isfinite(v) for v in values)


def _six(values: Sequence[float], what: str) -> None:
    """Refused unless `values` are 6 finite numbers (an offset or a pose); the message names what is wrong."""
    if len(values) != 6:
        raise Refused(say("manual.six_numbers_count", "{what} must be 6 numbers (x, y, z in m, rx, ry, rz in rad), "
                          "got {count}", what=what, count=len(values)))
    for axis, v in zip(AXES, values):
        if not _finite([v]):
            raise Refused(say("manual.six_numbers_value", "{what} must be 6 numbers (x, y, z in m, rx, ry, rz in rad), "
                              "got {value} for {axis}", what=what, value=repr(v), axis=axis))



def the_target(kind: str) -> Said:
    """"the relative target", "the pose target" (a move's target by its kind)."""
    if kind == RELATIVE:
        return say("manual.target_relative", "the relative target")
    return say("manual.target_pose", "the pose target")


def unknown_group(name: str, known: Sequence[str]) -> Said:
    return say("manual.unknown_group", "unknown motion group '{group}' (the cell has: {known})", group=name,
               known=", ".join(known) or "none")


def unknown_tool(name: str, known: Sequence[str]) -> Said:
    return say("manual.unknown_tool", "unknown tool '{tool}' (the cell has: {known})", tool=name,
               known=", ".join(known) or "none")


def unknown_frame(frame: str) -> Said:
    return say("manual.unknown_frame", "unknown frame '{frame}' (base or tool)", frame=frame)

class ManualDriver:
    def __init__(self, config: ManualConfig, host: str, connector: Connector, limits: Limits, *,
                 joint_names: Sequence[str] = UR_JOINTS, poll_rate: float = 125.0, retry_s: float = 1.0,
                 call_timeout: float = 1.0, clock: Callable[[], float] = time.monotonic,
                 sleep: Callable[[float], None] = time.sleep) -> None:
        self.config = config
        self.host = host
        self.limits = limits
        self.joint_names = tuple(joint_names)
        self.poll_period = 1.0 / poll_rate
        self.retry_s = retry_s
        self.call_timeout = call_timeout
        self.clock = clock
        self.sleep = sleep
        self._connector = connector
        self._gate = Gate(call_timeout)
        self._cmd_lock = threading.RLock()
        self._connect_lock = threading.Lock()
        self._recv: Optional[ReceiveInterface] = None
        self._io: Optional[IOInterface] = None
        self._ctl: Optional[ControlInterface] = None
        self._tcp_offset: list[float] = [0.0] * 6
        self._offset_known = False
        self._levers: dict[tuple[int, tuple[float, ...]], float] = {}
        self._connected = False
        self._was_connected = False
        self._snap = Snapshot()
        self._last_ts = (0.0, 0.0)              # (controller timestamp, our clock when it last changed)
        self._jog = JogSupervisor(limits.jog_timeout, clock)
        self._motion, self._group, self._target, self._progress = IDLE, "", "", 1.0
        self._token = 0                         # bumped by every new motion and by stop: ends a waiting call
        self._end_reason: str = say("manual.stopped", "stopped")
        self._sent: Optional[str] = None        # last motion command sent: "movej", "movel", "speedj", "speedl"
        self._message = ""
        self._fault = ""
        self._noted: tuple[int, str] = (0, "")   # the last press whose jog was not carried out, and why (logged once)
        self._threads: list[threading.Thread] = []
        self._stop_event = threading.Event()
        # The node sets these: on_change -> publish the state now; on_sample -> /joint_states after each poll.
        self.on_change: Callable[[], None] = lambda: None
        self.on_sample: Callable[[Snapshot], None] = lambda snap: None

    # ================================================================ lifecycle
    def start(self) -> None:
        """Connect (or keep retrying), then poll the robot and watch the jog heartbeat on background threads."""
        for target, name in ((self._monitor_loop, "manual-monitor"), (self._watchdog_loop, "manual-watchdog")):
            t = threading.Thread(target=target, name=name, daemon=True)
            t.start()
            self._threads.append(t)

    def shutdown(self) -> None:
        """Stop whatever moves, end the control script, let the clients go (all bounded in time)."""
        self._stop_event.set()
        try:
            if self._connected:
                self.stop(wait=False)
        except Exception:
            log.exception("stop at shutdown failed")
        for t in self._threads:
            t.join(1.0)
        clients = (self._ctl, self._io, self._recv)
        self._ctl = self._io = self._recv = None
        self._connected = False
        # In parallel: each ur_rtde disconnect takes ~0.5 s (it waits for its receive thread).
        closers = [threading.Thread(target=self._dispose, args=((c,), True), daemon=True) for c in clients if c]
        for t in closers:
            t.start()
        deadline = time.monotonic() + 2.0
        for t in closers:
            t.join(max(0.0, deadline - time.monotonic()))
        if any(t.is_alive() for t in closers):
            log.warning("the controller clients did not close in time")
        self._gate.close()

    # ================================================================ connection
    def connect(self) -> bool:
        """One attempt to reach the controller (receive + IO; the control script starts on the first command)."""
        with self._connect_lock:
            if self._connected:
                return True
            try:
                recv = cast(ReceiveInterface, Guarded(
                    run_with_timeout(lambda: self._connector.receive(self.host), 5.0, "ur-connect")))
            except Exception as e:
                log.debug("connect to %s failed: %s", self.host, e)
                # A backend that knows why (ros_control: no joint states, a URDF that does not load) says so.
                why = getattr(e, "reason", "")
                self._set_message(say("manual.unreachable_why", "{unreachable}: {why}", unreachable=self._unreachable(),
                                      why=why) if why else self._unreachable())
                return False
            try:
                io = cast(IOInterface, Guarded(
                    run_with_timeout(lambda: self._connector.io(self.host), 5.0, "ur-connect")))
            except Exception as e:
                log.debug("IO interface at %s failed: %s", self.host, e)
                self._dispose_later((recv,))
                self._set_message(self._unreachable())
                return False
            with self._cmd_lock:
                stale = (self._ctl, self._io, self._recv)  # normally none; never let a client be destroyed
                self._recv, self._io, self._ctl = recv, io, None
                self._levers.clear()
                self._last_ts = (-1.0, self.clock())
                self._connected = True
                self._message = (say("manual.reconnected", "reconnected to the robot controller at {host}",
                                     host=self.host) if self._was_connected
                                 else say("manual.connected", "connected to the robot controller at {host}",
                                          host=self.host))
                self._was_connected = True
            log.info(self._message)
        self._dispose_later(stale)
        self.poll()
        self.on_change()
        return True

    def _unreachable(self) -> Said:
        return say("manual.unreachable", "robot controller at {host} is unreachable", host=self.host)

    def _lose(self, why: str) -> None:
        """The controller is gone: forget the clients, end every motion, say so; the monitor reconnects."""
        with self._cmd_lock:
            if not self._connected:
                return
            clients = (self._ctl, self._io, self._recv)
            self._recv = self._io = self._ctl = None
            self._connected = False
            self._jog.clear()
            self._end_motion(self._unreachable())
            self._message = self._unreachable()
            self._snap = replace(self._snap, connected=False)
        log.warning("lost the robot controller at %s: %s", self.host, why)
        self._dispose_later(clients)
        self.on_change()

    def _dispose_later(self, clients: Sequence[object]) -> None:
        # Why threads, one per client: disconnecting from a controller that vanished can block (ur_rtde retries
        # inside), and a client waits for a call still inside it (Guarded.drop) without holding up the others.
        for c in clients:
            if c is not None:
                threading.Thread(target=self._dispose, args=((c,),), name="ur-dispose", daemon=True).start()

    @staticmethod
    def _dispose(clients: Sequence[object], stop_script: bool = False) -> None:
        for c in clients:
            if c is None:
                continue
            try:
                cast(Guarded, c).drop(stop_script)  # waits for a call still inside it (see Guarded)
            except Exception as e:
                log.debug("disconnect: %s", e)

    def _control(self, take_over: bool = True) -> ControlInterface:
        """The control client with its script running: made on first use, the script re-uploaded after it stopped
        (a protective stop or a runtime error ends it). Raises Refused when that cannot be done.
        take_over=False (calls that only read): never make it while another program runs on the controller, since
        starting the control script would end that program (the connector's `control_takes_over`)."""
        with self._connect_lock:
            ctl = self._ctl
            if ctl is not None:
                try:
                    alive = self._call(ctl.isConnected)
                except Refused:  # e.g. its process died (ur_process): the receive side may be fine, make a new one
                    alive = False
                if not alive:
                    self._dispose_later((ctl,))
                    self._ctl = ctl = None
            if ctl is None:
                if not self._connected:
                    raise Refused(self._unreachable())
                if not take_over and self._snap.program_running and \
                        getattr(self._connector, "control_takes_over", True):
                    raise Refused(say("manual.preview_other_program", "another program runs on the robot controller: "
                                      "a preview does not take it over (a move would stop it)"))
                try:
                    ctl = cast(ControlInterface, Guarded(
                        run_with_timeout(lambda: self._connector.control(self.host), 10.0, "ur-control")))
                except Exception as e:
                    raise Refused(say("manual.script_cannot_start", "cannot start the control script on the robot "
                                      "controller at {host}: {error}", host=self.host, error=e))
                with self._cmd_lock:
                    if not self._connected:  # lost while the client was being made
                        self._dispose_later((ctl,))
                        raise Refused(self._unreachable())
                    self._ctl = ctl
                    self._offset_known = False
                fresh = True
            else:
                fresh = False
            # A fresh client starts its script, taking the controller over as ur_rtde's own constructor would.
            if fresh or not self._call(ctl.isProgramRunning):
                log.info("starting the control script" if fresh else "control script not running: uploading it again")
                if not self._call(ctl.reuploadScript, timeout=5.0):
                    raise Refused(say("manual.script_not_started", "the robot's control script could not be started "
                                      "(is the robot in remote control?)"))
                # The controller compiles and starts it; a loaded host has taken 5.5 s.
                deadline = self.clock() + SCRIPT_START_S
                while not self._call(ctl.isProgramRunning):
                    if self.clock() > deadline:
                        raise Refused(say("manual.script_did_not_start", "the robot's control script did not start "
                                          "(is the robot in remote control?)"))
                    self.sleep(POLL_S)
            if not self._offset_known:  # (read through the script: once it runs)
                self._tcp_offset = list(self._call(ctl.getTCPOffset))
                self._offset_known = True
            return ctl

    def _call(self, fn: Callable[[], T], timeout: Optional[float] = None) -> T:
        """A controller call through the gate; a call that never comes back means the controller is lost."""
        try:
            return self._gate.call(fn, timeout)
        except CallTimeout as e:
            threading.Thread(target=self._lose, args=(str(e),), daemon=True).start()
            raise Refused(self._unreachable()) from None
        except ClientGone:  # a client of a connection already lost (see Guarded)
            raise Refused(self._unreachable()) from None
        except Refused:
            raise
        except Exception as e:  # ur_rtde raises RuntimeError with its own text: answer it, do not crash the call
            raise Refused(say("manual.controller_error", "the robot controller reported an error: {error}",
                              error=e)) from None

    # ================================================================ monitoring
    def _monitor_loop(self) -> None:
        next_try = 0.0
        while not self._stop_event.is_set():
            if not self._connected:
                if self.clock() >= next_try:
                    next_try = self.clock() + self.retry_s
                    try:
                        self.connect()
                    except Exception:
                        log.exception("connect failed")
                self._stop_event.wait(0.05)
                continue
            t0 = self.clock()
            try:
                self.poll()
            except Exception:
                log.exception("poll failed")
            self._stop_event.wait(max(0.0, self.poll_period - (self.clock() - t0)))

    def _watchdog_loop(self) -> None:
        while not self._stop_event.wait(POLL_S):
            try:
                self.check_heartbeat()
            except Exception:
                log.exception("jog watchdog failed")

    def poll(self) -> Optional[Snapshot]:
        """Read the robot once: update the state, notice a lost controller, settle stops; tell the node."""
        recv = self._recv
        if recv is None:
            return None
        try:
            snap = self._gate.call(lambda: read_snapshot(recv))
        except Exception as e:
            if self._recv is recv:  # (not a client already dropped: that connection is gone)
                self._lose(f"reading the robot state failed: {e}")
            return None
        if not snap.connected:
            self._lose("RTDE connection closed")
            return None
        now = self.clock()
        if snap.timestamp != self._last_ts[0]:
            self._last_ts = (snap.timestamp, now)
        elif now - self._last_ts[1] > STALE_S:
            self._lose(f"no data for {STALE_S:g} s")
            return None
        changed = False
        with self._cmd_lock:
            if self._recv is not recv:  # lost and reconnected meanwhile: this reading is stale
                return None
            old, self._snap = self._snap, snap
            if (old.robot_mode, old.safety_mode, old.program_running, old.connected) != \
                    (snap.robot_mode, snap.safety_mode, snap.program_running, snap.connected):
                changed = True
            if self._motion == JOGGING and not self._movable(snap):
                self._jog.clear()  # the controller stopped the arm itself
                self._set_idle(say("manual.jog_stopped_why", "jog stopped: {why}", why=self._not_movable_reason(snap)))
                changed = True
            elif self._motion == STOPPING and snap.standstill():
                self._set_idle(None)
                changed = True
        self.on_sample(snap)
        if changed:
            self.on_change()
        return snap

    def _read(self) -> Snapshot:
        """A fresh reading for a waiting service call (does not replace the monitor's)."""
        recv = self._recv
        if recv is None:
            raise Refused(self._unreachable())
        snap = self._call(lambda: read_snapshot(recv))
        if not snap.connected:
            raise Refused(self._unreachable())
        return snap

    # ================================================================ state
    def state(self) -> DriverState:
        s = self._snap
        return DriverState(connected=self._connected, controller=self.host,
                           robot_mode=s.robot_mode if self._connected else "NO_CONTROLLER",
                           safety_mode=s.safety_mode if self._connected else "",
                           speed_scaling=s.speed_scaling, program_running=s.program_running and self._connected,
                           motion=self._motion, motion_group=self._group, motion_target=self._target,
                           progress=self._progress, message=self._message, joint_positions=list(s.q),
                           tcp_pose=list(s.tcp_pose), tcp_speed=list(s.tcp_speed), fault=self._fault)

    def snapshot(self) -> Snapshot:
        return self._snap

    @property
    def connected(self) -> bool:
        return self._connected

    def _set_message(self, message: str) -> None:
        if message != self._message:
            self._message = message
            self.on_change()

    def _set_idle(self, message: Optional[str]) -> None:
        """Caller holds _cmd_lock."""
        self._motion, self._group, self._target, self._progress, self._sent = IDLE, "", "", 1.0, None
        if message is not None:
            self._message = message

    def _end_motion(self, reason: str) -> None:
        """End whatever runs (caller holds _cmd_lock): a waiting service call returns `reason`."""
        if self._motion != IDLE:
            self._token += 1
            self._end_reason = reason
        self._set_idle(None)

    # ================================================================ checks
    @staticmethod
    def _movable(s: Snapshot) -> bool:
        return s.robot_mode == "RUNNING" and s.safety_mode in MOVABLE_SAFETY

    @staticmethod
    def _not_movable_reason(s: Snapshot) -> Said:
        if s.robot_mode == "CONTROLLER_NOT_RUNNING":
            return say("manual.controller_not_running", "the arm's trajectory controller is not running (its action "
                       "server does not answer)")
        if s.robot_mode in ("POWER_ON", "IDLE"):
            return say("manual.brakes_not_released", "robot brakes are not released (mode {mode})", mode=s.robot_mode)
        if s.robot_mode != "RUNNING":
            return say("manual.not_powered", "robot is not powered on (mode {mode})", mode=s.robot_mode)
        if s.safety_mode == "PROTECTIVE_STOP":
            return say("manual.protective_stop", "protective stop is active: clear it first")
        if s.safety_mode in ("SAFEGUARD_STOP", "AUTOMATIC_MODE_SAFEGUARD_STOP"):
            return say("manual.safeguard_stop", "safeguard stop is active: close the guard first")
        if "EMERGENCY" in s.safety_mode:
            return say("manual.emergency_stop", "emergency stop is active ({mode}): release it first",
                       mode=s.safety_mode)
        return say("manual.safety_mode", "robot cannot move in safety mode {mode}", mode=s.safety_mode)

    def _check_robot(self) -> Snapshot:
        """Refuse unless the controller answers, the arm is powered and no safety stop is active."""
        if not self._connected:
            raise Refused(self._unreachable())
        s = self._snap
        if not self._movable(s):
            raise Refused(self._not_movable_reason(s))
        return s

    def _claim(self, motion: str, group: str, target: str) -> int:
        """Reserve the arm for a service command (refused if another one, or a jog, runs)."""
        deadline = self.clock() + 0.5
        while True:
            with self._cmd_lock:
                self._check_robot()
                if self._motion == IDLE:
                    self._token += 1
                    self._fault = ""
                    self._motion, self._group, self._target, self._progress = motion, group, target, 0.0
                    self._sent = None
                    token = self._token
                    break
                busy = self._motion != STOPPING or self.clock() > deadline
                what = "jog " + self._target if self._motion == JOGGING else self._target or self._motion
                if self._motion == JOGGING:  # any move request stops a jog (and is refused: nothing queues)
                    self._stop_jog(say("manual.jog_stopped_move", "jog stopped: a move was requested") if motion == MOVING
                                   else say("manual.jog_stopped_tool", "jog stopped: a tool action was requested"))
            if busy:
                raise Refused(say("manual.busy", "another move is running ({what}): stop it first", what=what))
            self.sleep(POLL_S)  # a stop is settling: it ends within ~0.3 s
        self.on_change()
        return token

    def _release(self, token: int, message: str) -> None:  # (a Said keeps its code)
        with self._cmd_lock:
            if self._token == token:
                self._set_idle(message)
            else:
                self._message = message
        self.on_change()

    def find_group(self, name: str) -> Group:
        g = self.config.groups.get(name)
        if g is None:
            raise Refused(unknown_group(name, self.config.groups))
        return g

    # ================================================================ services
    def groups(self) -> tuple[list[Group], list[tuple[str, list[str]]], Limits]:
        tools = [(t.name, list(t.actions)) for t in self.config.tools.values()]
        return list(self.config.groups.values()), tools, self.limits

    def get_pose(self, group: str) -> tuple[bool, str, list[float], list[float]]:
        try:
            g = self.find_group(group)
            s = self._read()
        except Refused as e:
            return False, e.said, [], []
        return True, say("manual.pose_of", "pose of {group}", group=g.name), [s.q[i] for i in g.indices], \
            list(s.tcp_pose)

    def move_named(self, group: str, name: str, speed: float = 0.0, acceleration: float = 0.0) -> tuple[bool, str]:
        return self._move(MoveRequest(NAMED, group, name=name), self.limits.joint_speed(speed),
                          self.limits.joint_acceleration(acceleration))

    def move_relative(self, group: str, offset: Sequence[float], frame: str, speed: float = 0.0,
                      acceleration: float = 0.0) -> tuple[bool, str]:
        return self._move(MoveRequest(RELATIVE, group, offset=tuple(offset), frame=frame),
                          self.limits.tcp_speed(speed), self.limits.tcp_acceleration(acceleration))

    def move_pose(self, group: str, pose: Sequence[float], speed: float = 0.0,
                  acceleration: float = 0.0) -> tuple[bool, str]:
        return self._move(MoveRequest(POSE, group, pose=tuple(pose)), self.limits.tcp_speed(speed),
                          self.limits.tcp_acceleration(acceleration))

    def _move(self, request: MoveRequest, speed: float, acc: float) -> tuple[bool, str]:
        """A move service: the request checked, the arm claimed, the target computed (move_target), then moved."""
        try:
            g = self.check_request(request)
            token = self._claim(MOVING, g.name, request.label)
        except Refused as e:
            return False, e.said
        try:
            target = self.move_target(request)
            run = self._linear_move if target.linear else self._joint_move
            return self._succeed(token, run(token, target, speed, acc))
        except Refused as e:
            return self._fail(token, e.said)

    def preview_move(self, group: str, kind: str, name: str = "", offset: Sequence[float] = (), frame: str = "",
                     pose: Sequence[float] = ()) -> tuple[bool, str, list[str], list[float], list[float]]:
        """/cell/manual/preview_move: (reachable, message, joint names, joint positions, TCP pose) of the target the
        move of this kind would go to now, computed by the move's own move_target. Moves nothing and never claims
        the arm, so it answers while a move or a jog runs; never starts the control script over another program.
        Not reachable: the move's own words (an unknown name, bad numbers, no IK solution, a joint limit, ...)."""
        request = MoveRequest(kind, group, name=name, offset=tuple(offset), frame=frame, pose=tuple(pose))
        try:
            target = self.move_target(request, take_over=False)
        except Refused as e:
            return False, e.said, [], [], []
        what = request.name if kind == NAMED else the_target(kind)
        return True, say("manual.reachable", "{what} is reachable", what=what), list(self.joint_names), \
            list(target.q), list(target.tcp_pose)

    # ================================================================ targets
    def check_request(self, request: MoveRequest) -> Group:
        """The checks a request passes before anything is asked of the robot; Refused with the move's words."""
        g = self.find_group(request.group)
        if request.kind == NAMED:
            if request.name not in g.configurations:
                raise Refused(say("manual.unknown_configuration", "unknown configuration '{name}' for group {group} "
                                  "(it has: {known})", name=request.name, group=g.name,
                                  known=", ".join(g.configurations) or "none"))
        elif request.kind == RELATIVE:
            _six(request.offset, say("manual.offset", "offset"))
            if (request.frame or "base") not in FRAMES:
                raise Refused(unknown_frame(request.frame))
        elif request.kind == POSE:
            _six(request.pose, say("manual.pose", "pose"))
        else:
            raise Refused(say("manual.unknown_kind", "unknown move kind '{kind}' (named, relative or pose)",
                              kind=request.kind))
        return g

    def move_target(self, request: MoveRequest, *, take_over: bool = True) -> MoveTarget:
        """Where `request` takes the arm from where it stands now: the one computation behind the move services, a
        tool's move_named step and the preview. Raises Refused with the move's words.

        - named: the group's joints at the configuration, the arm's other joints where they are; the TCP there
          from the controller's forward kinematics;
        - relative: frames.relative_target of the current TCP pose; pose: the pose as given; then the IK the linear
          move relies on: the controller's IK seeded with the current joints (ur_rtde, whose moveL does its own IK
          from there), or the backend's own moveL planning (getLinearMoveTarget: ros_control's waypoint IK);
        - then the joint target against the limits: the backend's own check (getJointLimitError: the URDF's
          limits, as ros_control's moveJ), else the controller's (isJointsWithinSafetyLimits).

        Moves nothing and claims nothing (safe while another move runs). take_over=False: see _control."""
        g = self.check_request(request)
        self._check_robot()
        ctl = self._control(take_over)
        start = self._read()
        q_now = list(start.q)
        if request.kind == NAMED:
            q = list(start.q)
            for i, v in zip(g.indices, g.configurations[request.name]):
                q[i] = v
            self._check_joint_target(ctl, q, say("manual.configuration", "configuration {name}", name=request.name))
            tcp = list(self._call(lambda: ctl.getForwardKinematics(q, list(self._tcp_offset))))
            return MoveTarget(g, request, start, tuple(q), tuple(tcp), linear=False)
        pose = (frames.relative_target(start.tcp_pose, request.offset, request.frame or "base")
                if request.kind == RELATIVE else [float(v) for v in request.pose])
        # Check first: IK (or a moveL) to a pose without solution ends ur_rtde's control script with a runtime error.
        if not self._call(lambda: ctl.getInverseKinematicsHasSolution(pose, q_now, 1e-10, 1e-10), timeout=5.0):
            raise Refused(say("manual.no_ik", "pose unreachable: no inverse kinematics solution"))
        plan = getattr(ctl, "getLinearMoveTarget", None)
        if plan is not None:
            q = list(self._call(lambda: plan(pose, q_now), timeout=5.0))
        else:
            q = list(self._call(lambda: ctl.getInverseKinematics(pose, q_now, 1e-10, 1e-10), timeout=5.0))
        if len(q) != len(q_now) or not _finite(q):
            raise Refused(say("manual.no_ik_answer", "pose unreachable: the controller gave no inverse kinematics "
                              "solution"))
        self._check_joint_target(ctl, q, the_target(request.kind))
        return MoveTarget(g, request, start, tuple(q), tuple(pose), linear=True)

    def _check_joint_target(self, ctl: ControlInterface, q: list[float], what: str) -> None:
        explain = getattr(ctl, "getJointLimitError", None)
        if explain is not None:
            why = self._call(lambda: explain(q))
            if why:
                raise Refused(why)
        elif not self._call(lambda: ctl.isJointsWithinSafetyLimits(q)):
            raise Refused(say("manual.outside_limits", "{what} is outside the robot's safety limits (joint limits, "
                              "safety planes or reach)", what=what))

    def tool_action(self, tool: str, action: str) -> tuple[bool, str]:
        label = f"{tool} {action}"
        try:
            t = self.config.tools.get(tool)
            if t is None:
                raise Refused(unknown_tool(tool, self.config.tools))
            a = t.actions.get(action)
            if a is None:
                raise Refused(say("manual.unknown_action", "unknown action '{action}' for tool {tool} (it has: {known})",
                                  action=action, tool=tool, known=", ".join(t.actions) or "none"))
            token = self._claim(TOOL, "", label)
        except Refused as e:
            return False, e.said
        try:
            n = len(a.steps)
            for i, step in enumerate(a.steps):
                self._progress = i / n if n else 0.0
                self._check_token(token)
                if isinstance(step, DigitalOut):
                    io = self._io
                    if io is None:
                        raise Refused(self._unreachable())
                    if not self._call(lambda: io.setStandardDigitalOut(step.output, step.value)):
                        raise Refused(say("manual.output_refused", "{label}: the controller refused digital output "
                                          "{output}", label=label, output=step.output))
                elif isinstance(step, Wait):
                    self._wait(token, step.seconds)
                elif isinstance(step, WaitInput):
                    self._wait_input(token, label, step)
                elif isinstance(step, MoveNamedStep):
                    try:
                        self._joint_move(token, self.move_target(MoveRequest(NAMED, step.group,
                                                                             name=step.configuration)),
                                         self.limits.default_speed, self.limits.default_acceleration)
                    except Refused as e:
                        self._check_token(token)
                        raise Refused(say("manual.tool_step_failed", "{label}: {why}", label=label,
                                          why=e.said)) from None
            return self._succeed(token, say("manual.tool_done", "{label} done", label=label))
        except Refused as e:
            return self._fail(token, e.said)

    def stop(self, wait: bool = True) -> tuple[bool, str]:
        """Stop any jog, move or tool action now; always allowed. Answers once the arm stands still (<= 1 s);
        success false only when the controller cannot be reached (nothing can be commanded then)."""
        with self._cmd_lock:
            was = self._motion
            self._jog.clear()
            sent = self._sent
            if was != IDLE:
                self._token += 1
                self._end_reason = say("manual.stopped", "stopped")
                self._motion, self._progress = STOPPING, 1.0
            self._message = say("manual.stopped", "stopped")
            if sent is not None:
                log.info("stopped (%s)", self._target or sent)
            ctl = self._ctl
            if ctl is not None and self._connected and sent is not None:
                try:
                    self._send_stop(ctl, sent)
                except Refused as e:
                    log.warning("stop: %s", e)
            self._sent = None
        foreign = sent is None and self._connected and self._snap.program_running and not self._snap.standstill()
        if foreign:
            # The arm moves, but not by a command of ours (another program runs on the controller): this is also
            # the app's "Stop robot", so stop that program the way PolyScope's stop button does.
            self._stop_program()
        self.on_change()
        settled = not self._connected
        if wait and self._connected:
            deadline = self.clock() + 1.0
            while not settled and self.clock() < deadline:
                try:
                    settled = self._read().standstill()
                except Refused:
                    settled = True  # the controller is gone: nothing left to stop
                if not settled:
                    self.sleep(POLL_S)
        with self._cmd_lock:
            # Not settled yet (or not waited for): the monitor turns "stopping" into "idle" at standstill.
            if self._motion == STOPPING and settled:
                self._set_idle(None)
            if not self._connected:
                self._message = self._unreachable()
        self.on_change()
        return (True, say("manual.stopped", "stopped")) if self._connected else (False, self._unreachable())

    def _stop_program(self) -> None:
        def run() -> None:
            db = self._connector.dashboard(self.host)
            keep_forever(db)  # like the RTDE clients: never destroyed (see keep_forever)
            db.connect(2000)
            try:
                db.stop()
            finally:
                db.disconnect()
        try:
            run_with_timeout(run, 3.0, "ur-dashboard")
            log.info("stopped the program running on the controller (dashboard stop)")
        except Exception as e:
            log.warning("dashboard stop failed: %s", e)

    def _send_stop(self, ctl: ControlInterface, sent: Optional[str], hard: bool = False) -> None:
        """Caller holds _cmd_lock. A firm stop fitting the command that runs (harder when heartbeats were lost)."""
        if sent == "speedj":
            self._call(lambda: ctl.speedStop(WATCHDOG_DECEL_JOINT if hard else STOP_DECEL_JOINT))
        elif sent == "speedl":
            self._call(lambda: ctl.speedStop(WATCHDOG_DECEL_TCP if hard else STOP_DECEL_TCP))
        elif sent == "movel":
            self._call(lambda: ctl.stopL(STOP_DECEL_TCP, True))
        else:
            self._call(lambda: ctl.stopJ(STOP_DECEL_JOINT, True))

    def _succeed(self, token: int, message: str) -> tuple[bool, str]:
        self._release(token, message)
        return True, message

    def _fail(self, token: int, message: str) -> tuple[bool, str]:
        with self._cmd_lock:
            if self._token != token:
                message = self._end_reason  # stopped, or the controller went away, while we waited
        self._release(token, message)
        return False, message

    def _check_token(self, token: int) -> None:
        if self._token != token:
            raise Refused(self._end_reason)

    def _wait(self, token: int, seconds: float) -> None:
        """A tool action's dwell, timed on the controller's clock (its RTDE timestamp), the time the tool lives in: a
        real controller keeps real time, a simulated one that falls behind on a loaded host (0.82 seen in the soak)
        still gets the whole dwell, so its fingers have opened before the arm lifts. At most 3x + 1 s of our clock."""
        start = self._read().timestamp
        wall_end = self.clock() + 3.0 * seconds + 1.0
        while self._read().timestamp - start < seconds and self.clock() < wall_end:
            self._check_token(token)
            self.sleep(POLL_S)
        self._check_token(token)

    def _wait_input(self, token: int, label: str, step: WaitInput) -> None:
        end = self.clock() + step.timeout_s
        while True:
            self._check_token(token)
            if bool(self._read().digital_in >> step.input & 1) == step.value:
                return
            if self.clock() > end:
                raise Refused(say("manual.input_timeout_on", "{label}: digital input {input} did not turn on within "
                                  "{seconds} s", label=label, input=step.input, seconds=f"{step.timeout_s:g}")
                              if step.value else
                              say("manual.input_timeout_off", "{label}: digital input {input} did not turn off within "
                                  "{seconds} s", label=label, input=step.input, seconds=f"{step.timeout_s:g}"))
            self.sleep(POLL_S)

    # ================================================================ moves
    def _joint_move(self, token: int, t: MoveTarget, speed: float, acc: float) -> Said:
        """Move to a named configuration's target (move_target); returns the success message, raises Refused."""
        ctl = self._ctl  # move_target made it
        if ctl is None:
            raise Refused(self._unreachable())
        start, target, name = t.start, list(t.q), t.request.name
        lead = max(abs(a - b) for a, b in zip(target, start.q))

        def progress(s: Snapshot) -> float:
            rest = max(abs(a - b) for a, b in zip(target, s.q))
            return 1.0 - rest / lead if lead > 1e-9 else 1.0

        def arrived(s: Snapshot) -> bool:
            return max(abs(a - b) for a, b in zip(target, s.q)) < JOINT_TOLERANCE

        with self._cmd_lock:
            self._check_token(token)
            if not self._call(lambda: ctl.moveJ(target, speed, acc, True)):
                raise Refused(say("manual.move_refused", "the controller refused the move to {name}", name=name))
            self._sent = "movej"
        self._await(token, progress, arrived, lead / speed + speed / acc)
        return say("manual.arrived_at", "arrived at {name}", name=name)

    def _linear_move(self, token: int, t: MoveTarget, speed: float, acc: float) -> Said:
        """A straight TCP line to the target's pose (move_target checked its IK); returns the success message,
        raises Refused."""
        ctl = self._ctl  # move_target made it
        if ctl is None:
            raise Refused(self._unreachable())
        start, pose, label = t.start, list(t.tcp_pose), t.request.label
        d0, a0 = frames.pose_distance(start.tcp_pose, pose)
        length = max(d0, a0 * 0.1)

        def progress(s: Snapshot) -> float:
            d, a = frames.pose_distance(s.tcp_pose, pose)
            return 1.0 - max(d, a * 0.1) / length if length > 1e-9 else 1.0

        def arrived(s: Snapshot) -> bool:
            d, a = frames.pose_distance(s.tcp_pose, pose)
            return d < POSITION_TOLERANCE and a < ANGLE_TOLERANCE

        with self._cmd_lock:
            self._check_token(token)
            if not self._call(lambda: ctl.moveL(pose, speed, acc, True)):
                raise Refused(say("manual.linear_refused_relative", "the controller refused the relative move")
                              if label == RELATIVE else
                              say("manual.linear_refused_pose", "the controller refused the pose move"))
            self._sent = "movel"
        self._await(token, progress, arrived, length / speed + speed / acc)
        return say("manual.arrived_at_target", "arrived at {target}", target=the_target(label))

    def _await(self, token: int, progress: Callable[[Snapshot], float], arrived: Callable[[Snapshot], bool],
               expected_s: float) -> None:
        """Wait for an asynchronous move: the controller's async progress, then the arm settling on the target.
        Raises Refused when it ends otherwise (stopped, safety stop, controller lost, script ended)."""
        ctl = self._ctl
        if ctl is None:
            raise Refused(self._unreachable())
        t0 = self.clock()
        # The speed slider stretches moves in time; beyond this something is wrong and the arm is stopped.
        limit = t0 + 3.0 * expected_s / max(self._snap.speed_scaling, 0.1) + 5.0
        seen_running = False
        done_at: Optional[float] = None
        while True:
            self._check_token(token)
            s = self._read()
            if not self._movable(s):
                raise Refused(say("manual.move_aborted", "move aborted: {why}", why=self._not_movable_reason(s)))
            running = self._call(ctl.getAsyncOperationProgress) >= 0
            error = self._call(ctl.getMoveError) if hasattr(ctl, "getMoveError") else ""
            if error:
                with self._cmd_lock:
                    if self._token == token:
                        self._fault = error
                raise MotionFault(error)
            seen_running = seen_running or running
            p = min(max(progress(s), 0.0), 1.0)
            if abs(p - self._progress) >= 0.01:
                self._progress = p
            now = self.clock()
            if not running and (seen_running or now - t0 > 0.2):
                if arrived(s) and s.standstill():
                    return
                done_at = done_at or now
                if not s.program_running:
                    raise Refused(say("manual.script_ended", "the controller stopped the move (its control script "
                                      "ended)"))
                if now - done_at > 1.5:
                    raise Refused(say("manual.ended_away", "the move ended away from its target"))
            if now > limit:
                self.stop(wait=False)
                raise Refused(say("manual.move_timeout", "the move did not finish within {seconds} s",
                                  seconds=f"{limit - t0:.0f}"))
            self.sleep(POLL_S)

    # ================================================================ jogging
    def jog(self, group: str, mode: str, axis: int, direction: int, speed: float, frame: str = "base",
            age_s: Optional[float] = None, press: int = 0) -> None:
        """One JogCommand. Never answers: what happened shows in the state's motion and message. age_s: how long
        ago the BFF let it through (None: unknown, e.g. published on ROS directly); press: the page's number for
        this press of the button (a jog stopped by a stop, a refusal or the controller stays stopped until a new
        one: jog.py)."""
        cmd = Jog(group, mode, int(axis), int(max(-1, min(1, direction))), float(speed), frame or "base", int(press))
        if cmd.direction == 0:
            self._stop_jog(say("manual.jog_stopped", "jog stopped"), released=True)
            return
        if age_s is not None and age_s > self._jog.timeout:
            # A late heartbeat (a stalled link or node delivering a backlog): it neither restarts motion the watchdog
            # stopped nor keeps a jog alive, nor moves the arm for a session that lost control since it was sent.
            self._set_message(say("manual.jog_late", "jog ignored: it arrived {age} s after it was sent (more than the "
                                  "jog timeout, {timeout} s)", age=f"{age_s:.2f}", timeout=f"{self._jog.timeout:.2f}"))
            self._note(cmd, "ignored: it came late", f" ({age_s:.2f} s after the BFF let it through)")
            return
        try:
            g = self.find_group(group)
            if mode not in (JOINT, CARTESIAN):
                raise Refused(say("manual.unknown_jog_mode", "unknown jog mode '{mode}' (joint or cartesian)", mode=mode))
            if mode == JOINT and not 0 <= cmd.axis < len(g.joints):
                raise Refused(say("manual.no_joint", "group {group} has no joint {joint}", group=g.name,
                                  joint=cmd.axis + 1))
            if mode == CARTESIAN and not 0 <= cmd.axis < 6:
                raise Refused(say("manual.unknown_axis", "unknown Cartesian axis {axis} (0..5 = X, Y, Z, RX, RY, RZ)",
                                  axis=cmd.axis))
            if mode == CARTESIAN and cmd.frame not in FRAMES:
                raise Refused(unknown_frame(cmd.frame))
            if self.limits.jog_fraction(cmd.speed) is None:
                raise Refused(say("manual.jog_speed_zero", "jog speed must be above 0"))
            if self._motion in (MOVING, TOOL):
                self._note(cmd, "ignored: a move is running")
                self._set_message(say("manual.jog_ignored_busy", "jog ignored: a move is running ({target})",
                                      target=self._target))
                return
            self._check_robot()
            if cmd.same_motion(self._jog.stopped):
                self._note(cmd, "held: this press was stopped")
                return  # (held: see jog.py; the state still says why it stopped)
            if self._jog.active is None or not cmd.same_motion(self._jog.active):
                self._control()  # may upload the control script: not while holding the command lock
        except Refused as e:
            self._note(cmd, "refused", f": {e.said}")
            self.refuse_jog(e.said)
            return
        with self._cmd_lock:
            if self._motion in (MOVING, TOOL):
                return
            decision = self._jog.command(cmd)
            if decision is Decision.HELD:
                self._note(cmd, "held: this press was stopped or released")
            if decision is not Decision.START:
                return
            try:
                self._start_jog(cmd, g)
                self._jog.started()
                log.info("jogging %s at %.0f %% (press %d)", cmd.label(), cmd.speed * 100, cmd.press)
                self._noted = (0, "")  # a jog that runs again: why it stops being carried out is worth a line again
            except Refused as e:
                self._note(cmd, "refused", f": {e.said}")
                self._jog.clear(hold=False)  # it never moved: the press's next heartbeat tries again
                self._set_idle(say("manual.jog_refused", "jog refused: {why}", why=e.said))
        self.on_change()

    def _note(self, cmd: Jog, what: str, detail: str = "") -> None:
        """Log once per press (and per run of its jog) why its jog was not carried out (its heartbeats come 20 times
        a second); `detail` (e.g. how late) is the first such heartbeat's."""
        if self._noted != (cmd.press, what):
            self._noted = (cmd.press, what)
            log.info("jog %s (press %d) %s%s", cmd.label(), cmd.press, what, detail)

    def refuse_jog(self, why: str) -> None:
        """A JogCommand that cannot be carried out: a running jog stops (never carry on after a bad or refused
        command), and the state's message says why. The cell driver also calls it for a group no arm has."""
        if self._jog.active is not None:
            self._stop_jog(say("manual.jog_refused", "jog refused: {why}", why=why))
        else:
            self._set_message(say("manual.jog_refused", "jog refused: {why}", why=why))

    def _start_jog(self, cmd: Jog, g: Group) -> None:
        """Caller holds _cmd_lock. Sends the new speed at once: it replaces the running jog's."""
        ctl = self._ctl
        if ctl is None:
            raise Refused(self._unreachable())
        s = self._snap
        if cmd.mode == JOINT:
            joint = g.indices[cmd.axis]
            qd = [0.0] * len(s.q)
            qd[joint] = cmd.direction * self.limits.joint_jog_speed(cmd.speed, self._lever(ctl, s.q, joint))
            if self._sent == "speedl":  # switching speed modes: stop the other first (no blending of the two)
                self._call(lambda: ctl.speedStop(STOP_DECEL_TCP))
            if not self._call(lambda: ctl.speedJ(qd, self.limits.max_acceleration, 0.0)):
                raise Refused(say("manual.joint_jog_refused", "the controller refused the joint jog"))
            self._sent = "speedj"
        else:
            twist = [0.0] * 6
            twist[cmd.axis] = cmd.direction * self.limits.cartesian_jog_speed(cmd.axis, cmd.speed)
            xd = frames.tool_twist_to_base(twist, s.tcp_pose) if cmd.frame == "tool" else twist
            if self._sent == "speedj":
                self._call(lambda: ctl.speedStop(STOP_DECEL_JOINT))
            if not self._call(lambda: ctl.speedL(xd, self.limits.cartesian_jog_acceleration(cmd.axis), 0.0)):
                raise Refused(say("manual.cartesian_jog_refused", "the controller refused the Cartesian jog"))
            self._sent = "speedl"
        self._token += 1
        self._fault = ""
        self._motion, self._group, self._target, self._progress = JOGGING, g.name, cmd.label(), 1.0
        self._message = say("manual.jogging", "jogging {jog}", jog=cmd.label())

    def _lever(self, ctl: ControlInterface, q: Sequence[float], joint: int) -> float:
        """TCP metres per radian of `joint` here (controller FK). Only the joints after it change that distance (the
        ones before move its axis and the TCP together), so it is cached per their positions."""
        key = (joint, tuple(round(v, 3) for v in q[joint + 1:]))
        if key not in self._levers:
            tcp = self._tcp_offset
            self._levers[key] = fk_lever(lambda qq: self._call(lambda: ctl.getForwardKinematics(list(qq), tcp)),
                                         q, joint)
            if len(self._levers) > 256:
                self._levers.clear()
        return self._levers[key]

    def _stop_jog(self, message: str, hard: bool = False, hold: bool = True, released: bool = False) -> None:
        with self._cmd_lock:
            jog = self._jog.clear(hold, released)
            if jog is None and self._motion != JOGGING:
                return
            sent, ctl = self._sent, self._ctl
            self._token += 1
            self._motion, self._progress, self._sent = STOPPING, 1.0, None
            self._message = message
            log.info("%s (%s)", message, jog.label() if jog is not None else self._target)
            if ctl is not None and self._connected:
                try:
                    self._send_stop(ctl, sent if sent in ("speedj", "speedl") else "speedj", hard)
                except Refused as e:
                    log.warning("jog stop: %s", e)
        self.on_change()

    def check_heartbeat(self) -> bool:
        """The watchdog: stop a jog whose heartbeats stopped. True when it stopped one."""
        with self._cmd_lock:  # re-entrant: a heartbeat cannot slip in between the check and the stop
            if not self._jog.expired():
                return False
            self._stop_jog(say("manual.jog_no_heartbeat", "jog stopped: no heartbeat for {seconds} s",
                               seconds=f"{self.limits.jog_timeout:g}"), hard=True)
        return True
