"""Executes ur_rtde's control-script register protocol natively (instead of interpreting its URScript).

Protocol (mirrors the script the client uploads): the command id arrives in input_int_register_0 (+offset),
arguments in input double/int registers. The controller answers in output_int_register_0: 1 = ready for a
command, 2 = done with it; the client then writes 0 and we answer ready again. Real-time commands (servo,
speed, force, watchdog) are applied and answered 'ready' immediately. output_int_register_1 and the first
output double registers carry results; output_int_register_2 reports async progress.
"""
from __future__ import annotations

import logging
import re
from typing import TYPE_CHECKING, Callable, Optional

import numpy as np

from . import kinematics as kin
from . import motion

if TYPE_CHECKING:
    from .controller import Controller

log = logging.getLogger("sim.executor")

READY, DONE = 1, 2
NO_CMD = 0
MOVEJ, MOVEJ_IK, MOVEL, MOVEL_FK = 1, 2, 3, 4
FORCE_MODE, FORCE_MODE_STOP, ZERO_FT_SENSOR = 6, 7, 8
SPEEDJ, SPEEDL, SERVOJ, SERVOC = 9, 10, 11, 12
SPEED_STOP, SERVO_STOP, SET_PAYLOAD = 15, 16, 17
TEACH_MODE, END_TEACH_MODE = 18, 19
SERVOL, GET_STEPTIME = 24, 26
GET_TARGET_WAYPOINT, SET_TCP, GET_IK_ARGS, PROTECTIVE_STOP = 28, 29, 30, 31
STOPL, STOPJ, SET_WATCHDOG = 33, 34, 35
IS_POSE_WITHIN_LIMITS, IS_JOINTS_WITHIN_LIMITS, GET_JOINT_TORQUES, POSE_TRANS, GET_TCP_OFFSET = 36, 37, 38, 39, 40
GET_FK_DEFAULT, GET_FK_ARGS, MOVE_PATH, GET_IK_DEFAULT, IS_STEADY = 43, 44, 45, 46, 47
GET_ACTUAL_TOOL_FLANGE_POSE, GET_IK_HAS_SOLUTION_DEFAULT, GET_IK_HAS_SOLUTION_ARGS = 58, 60, 61
STOP_SCRIPT = 255
# Commands the script treats as real-time: processed, then 'ready' straight away (the client never waits).
REALTIME = {24, 11, 9, 10, 6, 25, 26, 27, 38, 58, 66, 67, 68, 69, 70, 71}
WATCHDOG_CMD = 99
SETTLE_TICKS = 500  # at most 1 s waiting for the arm to settle before a blocking move reports done


def parse_offsets(script: str) -> tuple[int, int]:
    """Register offsets injected by ur_rtde (0, or 24 with use_upper_range_registers).

    ur_rtde inserts the value right after the marker comment, so it lands at the start of the next line:
    "global reg_offset_float = # float register offset\n24    global reg_offset_int = ...".
    """
    def find(kind: str) -> int:
        m = re.search(rf"#\s*{kind} register offset\s*\n\s*(\d+)", script) or \
            re.search(rf"reg_offset_{kind}\s*=\s*(\d+)", script)
        return int(m.group(1)) if m else 0
    return find("float"), find("int")


_PATH_LINE = re.compile(r"^\s*(movej|movel|movep)\((p?)\[([^\]]*)\]\s*,\s*a=([-\d.e+]+)\s*,\s*v=([-\d.e+]+)"
                        r"(?:\s*,\s*r=([-\d.e+]+))?\)", re.M)


def parse_move_path(script: str) -> list[tuple[str, bool, list[float], float, float]]:
    """Waypoints ur_rtde injected for moveJ/moveL paths: (kind, is_pose, values, a, v)."""
    body = script.split("def exec_move_path():", 1)
    if len(body) < 2:
        return []
    section = body[1].split("\n    thread ", 1)[0].split("\n    def ", 1)[0]
    out = []
    for m in _PATH_LINE.finditer(section):
        vals = [float(x) for x in m.group(3).split(",")]
        out.append((m.group(1), m.group(2) == "p", vals, float(m.group(4)), float(m.group(5))))
    return out


class ControlScriptProgram:
    """The running ur_rtde control script, executed natively against the controller."""

    name = "rtde_control"

    def __init__(self, script: str) -> None:
        self.f_off, self.i_off = parse_offsets(script)
        self.path = parse_move_path(script)
        self.executing = False           # a non-real-time command was taken; wait for NO_CMD before the next
        self.blocking: Optional[Callable[["Controller"], bool]] = None  # returns True when the command is done
        self.async_motion = False
        self.async_wr_count = 0
        self.async_op_id = 0
        self.speed: Optional[motion.SpeedJ] = None
        self.servo: Optional[motion.ServoJ] = None
        self.path_queue: list[tuple[str, bool, list[float], float, float]] = []
        self.path_index = 0
        self.started = False
        self.settle_ticks = 0

    # ---- register helpers ---------------------------------------------------------------------
    def _in_int(self, c: "Controller", i: int) -> int:
        return c.in_int[i + self.i_off]

    def _in_f(self, c: "Controller", i: int, n: int = 1) -> list[float]:
        return [c.in_double[i + k + self.f_off] for k in range(n)]

    def _out_int(self, c: "Controller", i: int, v: int) -> None:
        c.out_int[i + self.i_off] = int(v)

    def _out_f(self, c: "Controller", i: int, values) -> None:
        for k, v in enumerate(values):
            c.out_double[i + k + self.f_off] = float(v)

    def _async_progress(self, c: "Controller", value: int) -> None:
        """Same bit layout as the script: op id (bits 24-30), write count (16-23), running (15), progress."""
        self.async_wr_count = (self.async_wr_count + 1) % 128
        if value == 0:
            self.async_op_id = (self.async_op_id + 1) % 128
        reg = self.async_wr_count * 65536 + self.async_op_id * 16777216
        if value >= 0:
            reg += min(value, 32767) + 32768
        self._out_int(c, 2, reg)

    # ---- main loop (one pass per controller tick, like the script's sync()) -----------------
    def tick(self, c: "Controller") -> None:
        if not self.started:
            self.started = True
            self._async_progress(c, -1)
            self._out_int(c, 0, READY)
        if self.async_motion and not c.arm.busy():
            if self.path_queue:
                self._advance_path(c)
            else:
                self.async_motion = False
                self._async_progress(c, -1)
        if self.blocking is not None:
            if self.blocking(c):
                self.blocking = None
                self._out_int(c, 0, DONE)
            return
        cmd = self._in_int(c, 0)
        if cmd in REALTIME:
            self._process(c, cmd)
            self._out_int(c, 0, READY)
        elif cmd == NO_CMD:
            self.executing = False
            self._out_int(c, 0, READY)
        elif not self.executing:
            self.executing = True
            if self._process(c, cmd) and self.blocking is None:
                self._out_int(c, 0, DONE)

    def on_stop(self, c: "Controller") -> None:
        self.blocking = None
        self._out_int(c, 0, 0)

    # ---- commands -----------------------------------------------------------------------------
    def _process(self, c: "Controller", cmd: int) -> bool:
        """Run one command; returns False when the program ended (stop script)."""
        q_act, _ = c.actual()
        if cmd in (MOVEJ, MOVEJ_IK, MOVEL, MOVEL_FK):
            target = self._in_f(c, 0, 6)
            v, a = self._in_f(c, 6, 2)
            is_async = self._in_int(c, 1) == 1
            self._stop_streaming()
            if cmd == MOVEJ_IK:
                q = kin.inverse(target, c.arm.q_set, c.tcp)
                if q is None:
                    raise motion.MotionError("movej: no inverse kinematics solution")
                target = list(q)
            if cmd in (MOVEJ, MOVEJ_IK):
                m: motion.Motion = motion.JointMove(c.arm.q_set, np.array(target), v, a)
            else:
                pose = np.array(target) if cmd == MOVEL else kin.forward(target, c.tcp)
                m = motion.LinearMove(c.arm.q_set, pose, v, a, c.tcp)
            c.arm.start(m)
            self._start_motion(c, is_async)
        elif cmd == MOVE_PATH:
            self._stop_streaming()
            self.path_queue, self.path_index = list(self.path), 0
            is_async = self._in_int(c, 1) == 1
            self._advance_path(c, first=True)
            self._start_motion(c, is_async, path=True)
        elif cmd in (STOPJ, STOPL):
            decel = self._in_f(c, 0)[0]
            self.path_queue = []
            self._stop_streaming()
            if c.arm.busy() and not isinstance(c.arm.motion, motion.Stop):
                tcp_speed = None
                if cmd == STOPL:
                    tcp_speed = float(np.linalg.norm((kin.jacobian(c.arm.q_set, c.tcp) @ c.arm.qd_set)[:3]))
                c.arm.stop(decel, tcp_speed)
            if self.async_motion:
                self.async_motion = False
                self._async_progress(c, -1)
            if self._in_int(c, 1) != 1:  # synchronous stop: done when the arm stands still
                self.blocking = lambda ctl: not ctl.arm.busy()
        elif cmd == SPEEDJ or cmd == SPEEDL:
            vals = self._in_f(c, 0, 8)
            if self.speed is None or not isinstance(c.arm.motion, motion.SpeedJ) or \
                    isinstance(self.speed, motion.SpeedL) != (cmd == SPEEDL):
                self.speed = motion.SpeedL(c.arm.q_set, c.arm.qd_set, c.tcp) if cmd == SPEEDL \
                    else motion.SpeedJ(c.arm.q_set, c.arm.qd_set)
                c.arm.start(self.speed)
            self.speed.set_target(np.array(vals[:6]), vals[6])
        elif cmd == SPEED_STOP:
            # Like the script: stopj(a) after speedJ, stopl(a) after speedL (a also limits the rotation), with the
            # client's deceleration a (ur_rtde's speedStop(a=10.0)).
            if self.speed is not None:
                decel = self._in_f(c, 0)[0] or 10.0
                lead = None
                if isinstance(self.speed, motion.SpeedL):
                    twist = kin.jacobian(c.arm.q_set, c.tcp) @ c.arm.qd_set
                    lead = max(float(np.linalg.norm(twist[:3])), float(np.linalg.norm(twist[3:])))
                self.speed = None
                c.arm.stop(decel, lead)
        elif cmd == SERVOJ:
            vals = self._in_f(c, 0, 11)
            if self.servo is None or c.arm.motion is not self.servo:
                self.servo = motion.ServoJ(c.arm.q_set)
                c.arm.start(self.servo)
            self.servo.set_target(np.array(vals[:6]), vals[8], vals[9])
        elif cmd == SERVOL:
            vals = self._in_f(c, 0, 11)
            q = kin.inverse(vals[:6], c.arm.q_set, c.tcp, 1e-8, 1e-8, iterations=30)
            if q is not None:
                if self.servo is None or c.arm.motion is not self.servo:
                    self.servo = motion.ServoJ(c.arm.q_set)
                    c.arm.start(self.servo)
                self.servo.set_target(q, vals[8], vals[9])
        elif cmd == SERVO_STOP:
            if self.servo is not None:
                self.servo = None
                c.arm.stop(10.0)
        elif cmd == GET_IK_ARGS or cmd == GET_IK_DEFAULT or cmd in (GET_IK_HAS_SOLUTION_DEFAULT, GET_IK_HAS_SOLUTION_ARGS):
            pose = self._in_f(c, 0, 6)
            near = self._in_f(c, 6, 6) if cmd in (GET_IK_ARGS, GET_IK_HAS_SOLUTION_ARGS) else list(q_act)
            q = kin.inverse(pose, np.array(near), c.tcp)
            if cmd in (GET_IK_HAS_SOLUTION_DEFAULT, GET_IK_HAS_SOLUTION_ARGS):
                self._out_int(c, 1, 1 if q is not None else 0)
            elif q is None:
                c.runtime_error("get_inverse_kin: no solution")
                return False
            else:
                self._out_f(c, 0, q)
        elif cmd == GET_FK_DEFAULT:
            self._out_f(c, 0, kin.forward(q_act, c.tcp))
        elif cmd == GET_FK_ARGS:
            vals = self._in_f(c, 0, 12)
            tcp = vals[6:12] if any(vals[6:12]) else c.tcp
            self._out_f(c, 0, kin.forward(vals[:6], tcp))
        elif cmd == GET_ACTUAL_TOOL_FLANGE_POSE:
            self._out_f(c, 0, kin.forward(q_act))
        elif cmd == IS_STEADY:
            self._out_int(c, 1, 1 if c.is_steady() else 0)
        elif cmd == SET_TCP:
            c.tcp = np.array(self._in_f(c, 0, 6))
        elif cmd == GET_TCP_OFFSET:
            self._out_f(c, 0, c.tcp)
        elif cmd == POSE_TRANS:
            vals = self._in_f(c, 0, 12)
            self._out_f(c, 0, kin.matrix_to_pose(kin.pose_to_matrix(vals[:6]) @ kin.pose_to_matrix(vals[6:])))
        elif cmd == SET_PAYLOAD:
            c.payload = self._in_f(c, 0)[0]
        elif cmd == ZERO_FT_SENSOR:
            c.ft_zero = c.body.ft_wrench()
        elif cmd == GET_JOINT_TORQUES:
            self._out_f(c, 0, c.body.arm_state().torque)
        elif cmd == GET_STEPTIME:
            self._out_f(c, 0, [0.002])
        elif cmd == GET_TARGET_WAYPOINT:
            self._out_f(c, 0, kin.forward(c.arm.q_set, c.tcp))
        elif cmd == IS_JOINTS_WITHIN_LIMITS:
            q = self._in_f(c, 0, 6)
            self._out_int(c, 1, 1 if all(abs(x) <= kin.JOINT_LIMIT for x in q) else 0)
        elif cmd == IS_POSE_WITHIN_LIMITS:
            self._out_int(c, 1, 1 if kin.inverse(self._in_f(c, 0, 6), q_act, c.tcp) is not None else 0)
        elif cmd == PROTECTIVE_STOP:
            c.protective_stop("protective_stop")
            return False
        elif cmd in (SET_WATCHDOG, FORCE_MODE_STOP, TEACH_MODE, END_TEACH_MODE):
            log.info("command %d accepted (no effect in the simulator)", cmd)
        elif cmd == STOP_SCRIPT:
            log.info("stop script received")
            c.stop_program("ended (stop script)")
            return False
        else:
            # The real script silently ignores ids it does not know and reports done; we do too, and log it.
            log.warning("unsupported control-script command id %d ignored", cmd)
        return True

    def _stop_streaming(self) -> None:
        self.speed = None
        self.servo = None

    def _start_motion(self, c: "Controller", is_async: bool, path: bool = False) -> None:
        if is_async:
            self.async_motion = True
            self._async_progress(c, 0)
        else:
            def done(ctl: "Controller") -> bool:
                if ctl.arm.busy():
                    return False
                if path and self.path_queue:
                    self._advance_path(ctl)
                    return False
                q, qd = ctl.actual()
                self.settle_ticks += 1
                # Report done when the physics has settled on the setpoint (or after 0.3 s of trying).
                if ctl.arm.settled(q, qd):
                    self.settle_ticks = 0
                    return True
                if self.settle_ticks > SETTLE_TICKS:
                    log.warning("arm did not settle on the target (error %.2g rad); reporting done anyway",
                                float(np.max(np.abs(ctl.arm.q_set - q))))
                    self.settle_ticks = 0
                    return True
                return False
            self.blocking = done

    def _advance_path(self, c: "Controller", first: bool = False) -> None:
        """Start the next waypoint of an injected moveJ/moveL path (progress = waypoint index)."""
        if not self.path_queue:
            return
        kind, is_pose, vals, a, v = self.path_queue.pop(0)
        log.info("path waypoint %d: %s %s", self.path_index, kind, [round(x, 5) for x in vals])
        self._async_progress(c, self.path_index)
        self.path_index += 1
        if kind == "movej":
            q = vals if not is_pose else kin.inverse(vals, c.arm.q_set, c.tcp)
            if q is None:
                raise motion.MotionError("movej: no inverse kinematics solution")
            c.arm.start(motion.JointMove(c.arm.q_set, np.array(q), v, a))
        else:
            pose = np.array(vals) if is_pose else kin.forward(vals, c.tcp)
            c.arm.start(motion.LinearMove(c.arm.q_set, pose, v, a, c.tcp))
