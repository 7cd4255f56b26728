"""The emulated UR controller: robot/safety/program state, IO, registers, and the 500 Hz control loop.

Everything a UR reports over RTDE or the dashboard server lives here; the servers only translate.
One Controller per arm of the world (each on its own address, with its own safety, IO and registers); the
WorldLoop ticks them all and steps the one physics world once per tick between their halves.
Commands from other threads (RTDE inputs, dashboard, faults) take `lock` (one lock for the whole world: the physics
client is shared); the control loop takes it per tick.
"""
from __future__ import annotations

import logging
import threading
import time
from collections import deque
from enum import IntEnum
from typing import Callable, Optional, Protocol

import numpy as np

from . import kinematics as kin
from . import motion
from .safety import FaultBook, cell_faults
from .scene import DOOR_INPUT, GripperSpec
from .urdf import default_tcp
from .world import DT, ArmState, RobotArm, World

log = logging.getLogger("sim.controller")

CONTROLLER_VERSION = (5, 11, 6, 108949)       # reported over RTDE 'v' (major > 3: e-Series, 500 Hz)
POLYSCOPE_VERSION = "URSoftware 5.11.6.108949 (Aug 09 2022)"
SERIAL_NUMBER = "20235500042"
PROTECTIVE_STOP_UNLOCK_DELAY = 5.0            # s; real controllers refuse to unlock earlier
PROGRAM_START_DELAY = 0.05                    # s of sim time from script upload / play to PLAYING
POWER_UP_TIME = 0.5                           # s of sim time from "power on" to IDLE, and for brake release
PROTECTIVE_STOP_DECEL = 8.0                   # rad/s^2 (category 2 stop)
FORCE_LIMIT = 150.0                           # N at the wrist before the cell's force guard trips
FORCE_LIMIT_TICKS = 25                        # ... sustained for 50 ms
GRIPPER_DO = 0                                # the demo's gripper closes on standard digital output 0
QD_WINDOW = 10                                # ticks (20 ms) over which the reported joint speeds are taken
INTEGRAL_GAIN = 0.05                          # why: removes the steady sag of position control under gravity


class RobotMode(IntEnum):
    NO_CONTROLLER = -1
    DISCONNECTED = 0
    CONFIRM_SAFETY = 1
    BOOTING = 2
    POWER_OFF = 3
    POWER_ON = 4
    IDLE = 5
    BACKDRIVE = 6
    RUNNING = 7


class SafetyMode(IntEnum):
    NORMAL = 1
    REDUCED = 2
    PROTECTIVE_STOP = 3
    RECOVERY = 4
    SAFEGUARD_STOP = 5
    SYSTEM_EMERGENCY_STOP = 6
    ROBOT_EMERGENCY_STOP = 7
    VIOLATION = 8
    FAULT = 9


class RuntimeState(IntEnum):
    STOPPING = 0
    STOPPED = 1
    PLAYING = 2
    PAUSING = 3
    PAUSED = 4
    RESUMING = 5


class Program(Protocol):
    """Something the controller runs: the ur_rtde control script (register executor) or a loaded .urp."""
    name: str

    def tick(self, ctl: "Controller") -> None: ...

    def on_stop(self, ctl: "Controller") -> None: ...


class Snapshot:
    """Immutable-by-convention copy of everything RTDE can report, replaced once per tick."""
    __slots__ = ("timestamp", "target_q", "target_qd", "target_qdd", "actual_q", "actual_qd", "actual_current",
                 "actual_TCP_pose", "actual_TCP_speed", "actual_TCP_force", "target_TCP_pose", "target_TCP_speed",
                 "robot_mode", "safety_mode", "runtime_state", "robot_status_bits", "safety_status_bits",
                 "digital_in", "digital_out", "speed_scaling", "speed_slider", "out_int", "out_double",
                 "in_int", "in_double", "out_bits", "in_bits", "ft_raw", "tcp_force_scalar", "payload",
                 "finger_q", "tactile", "elbow_position")


class Arm:
    """Holds the joint setpoint, runs the active motion generator and drives the physics toward it."""

    def __init__(self, body: RobotArm) -> None:
        self.body = body
        q = body.arm_state().q
        self.q_set = q.copy()
        self.qd_set = np.zeros(6)
        self.qdd_set = np.zeros(6)
        self.motion: Optional[motion.Motion] = None
        self.bias = np.zeros(6)
        self.frozen = False

    def start(self, m: motion.Motion) -> None:
        self.motion = m
        self.frozen = False

    def stop(self, decel: float, tcp_speed: Optional[float] = None) -> None:
        self.motion = motion.Stop(self.q_set, self.qd_set, decel, tcp_speed)

    def freeze(self, q: np.ndarray) -> None:
        """Hold at q without integral action (in contact an integrator would keep building force)."""
        self.motion = None
        self.q_set, self.qd_set, self.bias = np.array(q, dtype=float), np.zeros(6), np.zeros(6)
        self.frozen = True

    def busy(self) -> bool:
        return self.motion is not None

    def tick(self, q_actual: np.ndarray, powered: bool, time_scale: float = 1.0) -> None:
        if not powered:  # brakes hold the arm where it was; no motion generator runs
            self.motion = None
            self.qd_set = np.zeros(6)
            self.bias += INTEGRAL_GAIN * (self.q_set - q_actual)
            self.body.hold(self.q_set + self.bias)
            return
        prev_qd = self.qd_set
        if self.motion is not None:
            # The speed slider scales program motion in time (like UR speed scaling); stops are never slowed.
            scale = 1.0 if isinstance(self.motion, motion.Stop) else max(time_scale, 1e-3)
            q, qd, done = self.motion.step(DT * scale)
            self.q_set, self.qd_set = np.asarray(q, dtype=float), np.asarray(qd, dtype=float) * scale
            if done:
                self.motion = None
                self.qd_set = np.zeros(6)
        self.qdd_set = (self.qd_set - prev_qd) / DT
        if not self.frozen:
            self.bias += INTEGRAL_GAIN * (self.q_set - q_actual)
        self.body.command_arm(self.q_set + self.bias, self.qd_set)

    def settled(self, q_actual: np.ndarray, qd_actual: np.ndarray) -> bool:
        return (self.motion is None and float(np.max(np.abs(self.q_set - q_actual))) < 2e-5
                and float(np.max(np.abs(qd_actual))) < 2e-3)


class Controller:
    def __init__(self, world: World, boot_powered: bool = True, body: Optional[RobotArm] = None,
                 lock: Optional[threading.RLock] = None, faults: Optional[FaultBook] = None,
                 fault_ids: Optional[dict[str, str]] = None,
                 program_start: float = PROGRAM_START_DELAY) -> None:
        self.world = world
        self.program_start = program_start
        self.body = body if body is not None else world.arms[0]
        self.tool = self.body.spec.tool
        self.lock = lock if lock is not None else threading.RLock()
        # This arm's faults in the cell's FaultBook: generic name (protective_stop, tool_fault, door_open, force_limit)
        # -> fault id (one arm: the plain names, gripper_fault/vacuum_fault; several: "<group>.<name>", see safety.py).
        table, ids = cell_faults([(self.body.group, self.tool.kind)])
        self.faults = faults if faults is not None else FaultBook(table)
        self.fault_ids = fault_ids or ids[0]
        self.sim_time = 0.0
        self.tcp = np.array(default_tcp(self.tool.kind))
        self.payload = 0.0
        self.arm = Arm(self.body)
        self.robot_mode = RobotMode.RUNNING if boot_powered else RobotMode.POWER_OFF
        self.safety_mode = SafetyMode.NORMAL
        self.runtime_state = RuntimeState.STOPPED
        self.program: Optional[Program] = None
        self._pending_program: Optional[tuple[float, Program]] = None
        self.loaded_program: Optional[str] = None
        self._mode_change_at: Optional[tuple[float, RobotMode]] = None
        self.protective_stop_at = 0.0
        self.door_open = False
        self.speed_slider = 1.0
        # Registers and IO (controller-wide, shared by every RTDE client, like on the real robot).
        self.in_int = [0] * 48
        self.in_double = [0.0] * 48
        self.out_int = [0] * 48
        self.out_double = [0.0] * 48
        self.in_bits = [False] * 128
        self.out_bits = [False] * 128
        self.std_do = 0
        self.conf_do = 0
        self.tool_do = 0
        self.digital_in = 0
        self.external_ft = [0.0] * 6
        self.ft_zero = np.zeros(6)
        self._over_force_ticks = 0
        self._q_before_overload = self.body.arm_state().q
        self._q_history: deque[np.ndarray] = deque(maxlen=50)
        self._q_window: deque[np.ndarray] = deque([self._q_before_overload], maxlen=QD_WINDOW + 1)
        self.tick_listeners: list[Callable[[Snapshot], None]] = []
        self.snapshot = self._make_snapshot()
        self.ticks = 0

    # ---- running ------------------------------------------------------------------------------
    def tick(self) -> None:
        """One controller tick with the physics step (a world with this one arm; else WorldLoop.tick)."""
        with self.lock:
            self.step_controls()
            self.world.step()
            self.after_step()
        self.notify()

    def step_controls(self) -> None:
        """First half of a tick (lock held): program, tool IO and this arm's joint commands for the next step."""
        self.sim_time += DT
        self.ticks += 1
        self._advance_mode()
        self._start_pending_program()
        q_now = self.snapshot.actual_q  # state after the previous step == state now (saves a query)
        if self.runtime_state == RuntimeState.PLAYING and self.program is not None:
            try:
                self.program.tick(self)
            except motion.MotionError as e:
                self.runtime_error(str(e))
        self.body.set_tool(bool(self.std_do & (1 << self._tool_output())))
        self.body.tick_tool()
        powered = self.robot_mode == RobotMode.RUNNING
        try:
            self.arm.tick(q_now, powered, self.speed_slider)
        except motion.MotionError as e:
            self.arm.motion = None
            self.arm.qd_set = np.zeros(6)
            self.runtime_error(str(e))

    def after_step(self) -> None:
        """Second half of a tick (lock held), after the physics step: the new state, the force guard."""
        st = self.body.arm_state()
        # The joints' speed as a controller estimates it from its encoders: the change of position over the last
        # QD_WINDOW ticks. PyBullet's own velocity state is not that: CI saw 0.0105 rad/s reported, the same value
        # across three tests, with the joints still (under 2 mrad in 0.4 s). A one-step difference is not either:
        # CI then saw a wrist at rest flicker by 1e-5 rad from step to step, 0.013 rad/s. Either kept the driver
        # from ever seeing a standstill. A constant speed reads exactly (a ramp 10 ms late).
        self._q_window.append(st.q)
        st.qd = (st.q - self._q_window[0]) / (DT * max(len(self._q_window) - 1, 1))
        self.snapshot = self._make_snapshot(st)
        self._check_force_limit()

    def notify(self) -> None:
        for fn in self.tick_listeners:
            fn(self.snapshot)

    def _tool_output(self) -> int:
        return self.tool.close_output if isinstance(self.tool, GripperSpec) else self.tool.suction_output

    def _advance_mode(self) -> None:
        if self._mode_change_at and self.sim_time >= self._mode_change_at[0]:
            self.robot_mode = self._mode_change_at[1]
            self._mode_change_at = None

    def _make_snapshot(self, st: Optional[ArmState] = None) -> Snapshot:
        s = Snapshot()
        st = st or self.body.arm_state()
        s.timestamp = self.sim_time
        s.actual_q, s.actual_qd = st.q, st.qd
        s.actual_current = st.torque / 10.0  # nominal torque constant ~10 N m / A
        s.target_q, s.target_qd, s.target_qdd = self.arm.q_set.copy(), self.arm.qd_set.copy(), self.arm.qdd_set.copy()
        # Why pybullet's FK and not sim.kinematics here: it is C++ and this runs 500 times a second; the URDF
        # matches the DH model to 1e-6 m (tests/test_kinematics.py).
        tcp_quat = self._tcp_quat()
        _, flange_orn, tpos, torn, v_tcp, w = self.body.tcp_state(self.tcp[:3], tcp_quat)
        s.actual_TCP_pose = np.array([*tpos, *kin.quat_to_rotvec(torn)])
        s.actual_TCP_speed = np.array([*v_tcp, *w])
        s.elbow_position = np.array(self.body.elbow_position())
        if self.arm.motion is None and not self.arm.qd_set.any():
            s.target_TCP_pose = self._target_pose_cache(s.target_q)
        else:
            s.target_TCP_pose = kin.forward(s.target_q, self.tcp)
        s.target_TCP_speed = s.actual_TCP_speed  # why: a second Jacobian per tick costs more than it tells
        raw = self.body.ft_wrench() - self.ft_zero
        s.ft_raw = raw
        rot = np.array(self.world.p.getMatrixFromQuaternion(flange_orn)).reshape(3, 3)
        s.actual_TCP_force = np.concatenate([rot @ raw[:3], rot @ raw[3:]])  # sensor frame -> base frame
        s.tcp_force_scalar = float(np.linalg.norm(raw[:3]))
        s.robot_mode = int(self.robot_mode)
        s.safety_mode = int(self.safety_mode)
        s.runtime_state = int(self.runtime_state)
        powered = self.robot_mode in (RobotMode.POWER_ON, RobotMode.IDLE, RobotMode.RUNNING)
        s.robot_status_bits = (1 if powered else 0) | (2 if self.runtime_state == RuntimeState.PLAYING else 0)
        s.safety_status_bits = self._safety_bits()
        s.finger_q = self.body.finger_positions()
        s.digital_in = self._digital_inputs(s.finger_q)
        s.digital_out = self.std_do | (self.conf_do << 8) | (self.tool_do << 16)
        s.speed_scaling = 0.0 if self.safety_mode != SafetyMode.NORMAL else self.speed_slider
        s.speed_slider = self.speed_slider
        s.out_int, s.out_double = list(self.out_int), list(self.out_double)
        s.in_int, s.in_double = list(self.in_int), list(self.in_double)
        s.out_bits, s.in_bits = list(self.out_bits), list(self.in_bits)
        s.payload = self.payload
        s.tactile = None  # computed on demand by the sensor publisher (contact queries are not free)
        return s

    def _tcp_quat(self) -> tuple:
        key = tuple(self.tcp[3:])
        if getattr(self, "_tcp_quat_key", None) != key:
            self._tcp_quat_key = key
            self._tcp_quat_val = tuple(kin.matrix_to_quat(kin.rotvec_to_matrix(self.tcp[3:])))
        return self._tcp_quat_val

    def _target_pose_cache(self, q: np.ndarray) -> np.ndarray:
        """While the setpoint stands still its pose does not change: compute it once."""
        key = (q.tobytes(), self.tcp.tobytes())
        if getattr(self, "_target_key", None) != key:
            self._target_key = key
            self._target_pose = kin.forward(q, self.tcp)
        return self._target_pose

    def _safety_bits(self) -> int:
        m = self.safety_mode
        bits = 0
        if m == SafetyMode.NORMAL:
            bits |= 1 << 0
        if m == SafetyMode.REDUCED:
            bits |= 1 << 1
        if m == SafetyMode.PROTECTIVE_STOP:
            bits |= (1 << 2) | (1 << 10)
        if m == SafetyMode.RECOVERY:
            bits |= 1 << 3
        if m == SafetyMode.SAFEGUARD_STOP:
            bits |= (1 << 4) | (1 << 10)
        if m in (SafetyMode.SYSTEM_EMERGENCY_STOP, SafetyMode.ROBOT_EMERGENCY_STOP):
            bits |= (1 << 7) | (1 << 10) | (1 << (5 if m == SafetyMode.SYSTEM_EMERGENCY_STOP else 6))
        if m == SafetyMode.VIOLATION:
            bits |= 1 << 8
        if m == SafetyMode.FAULT:
            bits |= 1 << 9
        return bits

    def _digital_inputs(self, fingers: list[float]) -> int:
        """DI0: door closed (safeguard circuit); the tool's inputs (the demo's gripper: DI1 closed, DI2 part detected
        between the fingers; a vacuum tool: its input reads a part held on the cup)."""
        bits = 0 if self.door_open else 1 << DOOR_INPUT
        if isinstance(self.tool, GripperSpec):
            closed = self.body.gripper_closed
            part = closed and min(fingers) > 0.003
            return bits | ((1 if closed else 0) << self.tool.closed_input) | ((1 if part else 0) << self.tool.part_input)
        return bits | ((1 if self.body.held is not None else 0) << self.tool.vacuum_input)

    # ---- IO and registers (RTDE inputs) -------------------------------------------------------
    def apply_inputs(self, values: dict[str, object]) -> None:
        """Apply one RTDE input data package atomically (a command and its arguments land together)."""
        with self.lock:
            std_mask = values.get("standard_digital_output_mask")
            conf_mask = values.get("configurable_digital_output_mask")
            tool_mask = values.get("tool_digital_output_mask")
            for name, v in values.items():
                if name.startswith("input_int_register_"):
                    self.in_int[int(name.rsplit("_", 1)[1])] = int(v)  # type: ignore[arg-type]
                elif name.startswith("input_double_register_"):
                    self.in_double[int(name.rsplit("_", 1)[1])] = float(v)  # type: ignore[arg-type]
                elif name.startswith("input_bit_register_"):
                    self.in_bits[int(name.rsplit("_", 1)[1])] = bool(v)
                elif name == "input_bit_registers0_to_31":
                    for i in range(32):
                        self.in_bits[i] = bool(int(v) >> i & 1)  # type: ignore[call-overload]
                elif name == "input_bit_registers32_to_63":
                    for i in range(32):
                        self.in_bits[32 + i] = bool(int(v) >> i & 1)  # type: ignore[call-overload]
                elif name == "speed_slider_fraction" and values.get("speed_slider_mask", 0):
                    self.speed_slider = min(max(float(v), 0.0), 1.0)  # type: ignore[arg-type]
                elif name == "external_force_torque":
                    self.external_ft = list(v)  # type: ignore[call-overload]
            if std_mask is not None and "standard_digital_output" in values:
                self.std_do = _masked(self.std_do, int(std_mask), int(values["standard_digital_output"]))  # type: ignore[arg-type]
            if conf_mask is not None and "configurable_digital_output" in values:
                self.conf_do = _masked(self.conf_do, int(conf_mask), int(values["configurable_digital_output"]))  # type: ignore[arg-type]
            if tool_mask is not None and "tool_digital_output" in values:
                self.tool_do = _masked(self.tool_do, int(tool_mask), int(values["tool_digital_output"]))  # type: ignore[arg-type]

    def set_digital_out(self, n: int, value: bool) -> None:
        with self.lock:
            self.std_do = _masked(self.std_do, 1 << n, (1 << n) if value else 0)

    # ---- programs -----------------------------------------------------------------------------
    def start_program(self, program: Program) -> bool:
        """Run a program (script upload or dashboard play). Refused unless the arm is powered and safe."""
        with self.lock:
            if self.robot_mode != RobotMode.RUNNING or self.safety_mode != SafetyMode.NORMAL:
                log.warning("program %s refused: robot mode %s, safety mode %s", program.name,
                            self.robot_mode.name, self.safety_mode.name)
                return False
            if self.program is not None:
                self.stop_program()
            # Like a real controller (which compiles first), start a little later: this also lets the
            # client's register clear, sent just before the upload on another socket, land first.
            self._pending_program = (self.sim_time + self.program_start, program)
            return True

    def _start_pending_program(self) -> None:
        if self._pending_program and self.sim_time >= self._pending_program[0]:
            program = self._pending_program[1]
            self._pending_program = None
            if self.robot_mode != RobotMode.RUNNING or self.safety_mode != SafetyMode.NORMAL:
                log.warning("program %s not started: robot no longer ready", program.name)
                return
            self.program = program
            self.runtime_state = RuntimeState.PLAYING
            log.info("program %s started", program.name)

    def stop_program(self, reason: str = "stopped") -> None:
        with self.lock:
            self._pending_program = None
            if self.program is not None:
                log.info("program %s %s", self.program.name, reason)
                try:
                    self.program.on_stop(self)
                finally:
                    self.program = None
            if self.arm.busy() and not isinstance(self.arm.motion, motion.Stop):
                self.arm.stop(4.0)
            self.runtime_state = RuntimeState.STOPPED

    def pause_program(self) -> bool:
        with self.lock:
            if self.runtime_state != RuntimeState.PLAYING:
                return False
            self.runtime_state = RuntimeState.PAUSED
            if self.arm.busy():
                self.arm.stop(4.0)
            return True

    def resume_program(self) -> bool:
        with self.lock:
            if self.runtime_state != RuntimeState.PAUSED or self.robot_mode != RobotMode.RUNNING \
                    or self.safety_mode != SafetyMode.NORMAL:
                return False
            self.runtime_state = RuntimeState.PLAYING
            return True

    def runtime_error(self, message: str) -> None:
        """A script runtime error: the controller logs it and stops the program (the pendant shows a popup)."""
        log.error("runtime error: %s", message)
        self.stop_program("stopped by runtime error")

    # ---- power and safety (dashboard + faults) ------------------------------------------------
    def power_on(self) -> None:
        with self.lock:
            if self.robot_mode == RobotMode.POWER_OFF:
                self.robot_mode = RobotMode.POWER_ON
                self._mode_change_at = (self.sim_time + POWER_UP_TIME, RobotMode.IDLE)

    def power_off(self) -> None:
        with self.lock:
            self.stop_program("stopped by power off")
            self.robot_mode = RobotMode.POWER_OFF
            self._mode_change_at = None

    def brake_release(self) -> None:
        with self.lock:
            if self.robot_mode == RobotMode.POWER_OFF:
                self.power_on()
            target_time = max(self.sim_time, self._mode_change_at[0] if self._mode_change_at else 0.0)
            if self.robot_mode in (RobotMode.POWER_ON, RobotMode.IDLE):
                self._mode_change_at = (target_time + POWER_UP_TIME, RobotMode.RUNNING)

    def protective_stop(self, cause: str = "protective_stop") -> None:
        """Category-2 stop: decelerate, hold, stop the program; needs an unlock (>= 5 s later)."""
        with self.lock:
            if self.safety_mode != SafetyMode.PROTECTIVE_STOP:
                log.warning("protective stop (%s) of the arm of group %s", cause, self.body.group)
                self.safety_mode = SafetyMode.PROTECTIVE_STOP
                self.protective_stop_at = self.sim_time
                if cause == "force_limit":
                    # A collision: hold where the arm is instead of pushing on toward the setpoint.
                    self.arm.freeze(self._q_before_overload)
                else:
                    self.arm.stop(PROTECTIVE_STOP_DECEL)
                self.stop_program("stopped by protective stop")
        self.faults.set(self.fault_ids["protective_stop"], True)
        if cause == "force_limit":
            self.faults.set(self.fault_ids["force_limit"], True)

    def unlock_protective_stop(self, force: bool = False) -> bool:
        with self.lock:
            if self.safety_mode != SafetyMode.PROTECTIVE_STOP:
                return True
            if not force and self.sim_time - self.protective_stop_at < PROTECTIVE_STOP_UNLOCK_DELAY:
                return False
            self.safety_mode = SafetyMode.SAFEGUARD_STOP if self.door_open else SafetyMode.NORMAL
        self.faults.set(self.fault_ids["protective_stop"], False)
        self.faults.set(self.fault_ids["force_limit"], False)
        return True

    def set_door_open(self, is_open: bool) -> None:
        """The cell door is wired to the safeguard stop input: open -> safeguard stop, closed -> auto reset."""
        with self.lock:
            self.door_open = is_open
            if is_open and self.safety_mode == SafetyMode.NORMAL:
                self.safety_mode = SafetyMode.SAFEGUARD_STOP
                self.arm.stop(PROTECTIVE_STOP_DECEL)
                if self.runtime_state == RuntimeState.PLAYING:
                    self.runtime_state = RuntimeState.PAUSED
            elif not is_open and self.safety_mode == SafetyMode.SAFEGUARD_STOP:
                self.safety_mode = SafetyMode.NORMAL
                if self.runtime_state == RuntimeState.PAUSED and self.program is not None:
                    self.runtime_state = RuntimeState.PLAYING
        self.faults.set(self.fault_ids["door_open"], is_open)

    def set_gripper_fault(self, active: bool) -> None:
        """A tool fault (gripper or vacuum): the tool ignores its output until reset."""
        with self.lock:
            self.body.freeze_gripper(active)
        self.faults.set(self.fault_ids["tool_fault"], active)

    @property
    def fault_names(self) -> tuple[str, ...]:
        """What trigger_fault takes for this arm (the tool fault is named after the tool: gripper_fault, ...)."""
        return ("protective_stop", f"{self.tool.kind}_fault", "door_open", "force_limit", "reset")

    def trigger_fault(self, fault: str) -> tuple[bool, str]:
        """The /sim/trigger_fault service: inject a fault, or 'reset' to clear them all."""
        if fault == "protective_stop":
            self.protective_stop("protective_stop")
        elif fault == "force_limit":
            self.protective_stop("force_limit")
        elif fault == "door_open":
            self.set_door_open(True)
        elif fault == f"{self.tool.kind}_fault":
            self.set_gripper_fault(True)
        elif fault == "reset":
            self.set_door_open(False)
            self.set_gripper_fault(False)
            self.unlock_protective_stop(force=True)
        else:
            return False, f"unknown fault '{fault}' ({', '.join(self.fault_names)})"
        return True, f"{fault} done"

    def _check_force_limit(self) -> None:
        """Trip only on a sustained overload (like the real force guard), not on one solver spike."""
        over = self.snapshot.tcp_force_scalar > FORCE_LIMIT
        self._q_history.append(self.snapshot.actual_q)
        if not over:
            # Where the arm was ~0.1 s before the overload began: there the tool was still clear of the
            # obstacle, so holding there after the stop relieves the contact instead of pressing on.
            self._q_before_overload = self._q_history[0]
        self._over_force_ticks = self._over_force_ticks + 1 if over else 0
        if self._over_force_ticks >= FORCE_LIMIT_TICKS and self.safety_mode == SafetyMode.NORMAL \
                and self.robot_mode == RobotMode.RUNNING:
            self.protective_stop("force_limit")

    # ---- queries used by the executor --------------------------------------------------------
    def actual(self) -> tuple[np.ndarray, np.ndarray]:
        return self.snapshot.actual_q, self.snapshot.actual_qd

    def is_steady(self) -> bool:
        q, qd = self.actual()
        return self.arm.motion is None and float(np.max(np.abs(qd))) < 1e-3


def _masked(current: int, mask: int, value: int) -> int:
    return (current & ~mask) | (value & mask)


class WorldLoop:
    """Ticks every arm's controller and steps the one physics world once per tick, at DT of sim time per DT/speed
    of wall time (falling behind: resync instead of bursting).

    Per tick, under the world lock: each controller runs its program and commands its own arm (step_controls), the
    physics steps once for the whole world, then each controller reads its arm's new state and checks its own force
    guard (after_step). The tick listeners (RTDE streams wait on nothing: they read `snapshot`) run outside the lock.
    """

    def __init__(self, world: World, controllers: list[Controller], lock: threading.RLock) -> None:
        self.world, self.controllers, self.lock = world, controllers, lock
        self._stop_event = threading.Event()
        self._thread: Optional[threading.Thread] = None

    @property
    def sim_time(self) -> float:
        return self.controllers[0].sim_time

    def tick(self) -> None:
        with self.lock:
            for c in self.controllers:
                c.step_controls()
            self.world.step()
            for c in self.controllers:
                c.after_step()
        for c in self.controllers:
            c.notify()

    def start(self, speed: float = 1.0) -> None:
        self._thread = threading.Thread(target=self._run, args=(speed,), name="controller", daemon=True)
        self._thread.start()

    def stop(self) -> None:
        self._stop_event.set()
        if self._thread is not None:
            self._thread.join(2.0)

    def _run(self, speed: float) -> None:
        period = DT / speed
        next_t = time.perf_counter()
        while not self._stop_event.is_set():
            try:
                self.tick()
            except Exception:  # never let one bad tick kill the controllers
                log.exception("controller tick failed")
            next_t += period
            delay = next_t - time.perf_counter()
            if delay > 0:
                time.sleep(delay)
            elif delay < -0.05:
                next_t = time.perf_counter()
