"""RTDE server (port 30004): recipes, start/pause, output streaming at the client's frequency, input packages.

One thread per client does both directions: it waits on the socket until the next output package is due.
"""
from __future__ import annotations

import logging
import select
import socket
import struct
import time
from typing import Any, Callable, Optional

from . import rtde_protocol as rp
from .controller import CONTROLLER_VERSION, Controller, Snapshot
from .tcp import TcpServer

log = logging.getLogger("sim.rtde")

MAX_FREQUENCY = 500.0  # e-Series
CATCH_UP = 0.02        # s of late packages we still send (thread wake-ups jitter by a few ms in Python)


def _getter(name: str) -> Optional[Callable[[Snapshot], Any]]:
    """How to read one output variable from a controller snapshot."""
    direct = {
        "timestamp": lambda s: s.timestamp, "target_q": lambda s: s.target_q, "target_qd": lambda s: s.target_qd,
        "target_qdd": lambda s: s.target_qdd, "actual_q": lambda s: s.actual_q, "actual_qd": lambda s: s.actual_qd,
        "actual_current": lambda s: s.actual_current, "target_current": lambda s: s.actual_current,
        "target_moment": lambda s: s.actual_current * 10.0, "actual_current_window": lambda s: [0.0] * 6,
        "joint_control_output": lambda s: s.actual_current,
        "actual_TCP_pose": lambda s: s.actual_TCP_pose, "actual_TCP_speed": lambda s: s.actual_TCP_speed,
        "actual_TCP_force": lambda s: s.actual_TCP_force, "target_TCP_pose": lambda s: s.target_TCP_pose,
        "target_TCP_speed": lambda s: s.target_TCP_speed, "ft_raw_wrench": lambda s: s.ft_raw,
        "actual_digital_input_bits": lambda s: s.digital_in, "actual_digital_output_bits": lambda s: s.digital_out,
        "joint_temperatures": lambda s: [32.0] * 6, "actual_execution_time": lambda s: 0.2,
        "robot_mode": lambda s: s.robot_mode, "joint_mode": lambda s: [253 if s.robot_mode >= 5 else 239] * 6,  # running / power off
        "safety_mode": lambda s: s.safety_mode, "safety_status": lambda s: s.safety_mode,
        "actual_tool_accelerometer": lambda s: [0.0, 0.0, 9.81], "speed_scaling": lambda s: s.speed_scaling,
        "target_speed_fraction": lambda s: s.speed_slider, "actual_momentum": lambda s: 0.0,
        "actual_main_voltage": lambda s: 48.0, "actual_robot_voltage": lambda s: 48.0 if s.robot_mode >= 4 else 0.0,
        "actual_robot_current": lambda s: 0.8 if s.robot_mode >= 4 else 0.0, "actual_joint_voltage": lambda s: [48.0] * 6,
        "runtime_state": lambda s: s.runtime_state, "elbow_position": lambda s: s.elbow_position,
        "elbow_velocity": lambda s: [0.0] * 3, "robot_status_bits": lambda s: s.robot_status_bits,
        "safety_status_bits": lambda s: s.safety_status_bits, "tcp_force_scalar": lambda s: s.tcp_force_scalar,
        "payload": lambda s: s.payload, "payload_cog": lambda s: [0.0] * 3, "payload_inertia": lambda s: [0.0] * 6,
        "output_bit_registers0_to_31": lambda s: _bits(s.out_bits, 0),
        "output_bit_registers32_to_63": lambda s: _bits(s.out_bits, 32),
        "input_bit_registers0_to_31": lambda s: _bits(s.in_bits, 0),
        "input_bit_registers32_to_63": lambda s: _bits(s.in_bits, 32),
        "tool_output_voltage": lambda s: 24, "tool_temperature": lambda s: 30.0,
    }
    if name in direct:
        return direct[name]
    for prefix, attr in (("output_int_register_", "out_int"), ("output_double_register_", "out_double"),
                         ("input_int_register_", "in_int"), ("input_double_register_", "in_double"),
                         ("output_bit_register_", "out_bits"), ("input_bit_register_", "in_bits")):
        if name.startswith(prefix):
            idx = int(name[len(prefix):])
            return lambda s, a=attr, i=idx: getattr(s, a)[i]
    if name in rp.OUTPUT_TYPES:  # known variable we do not model: a plausible constant
        t = rp.OUTPUT_TYPES[name]
        zero: Any = [0.0] * 6 if t == "VECTOR6D" else [0.0] * 3 if t == "VECTOR3D" else \
            [0] * 6 if t.startswith("VECTOR6") else 0.0 if t == "DOUBLE" else 0
        return lambda s: zero
    return None


def _bits(bits: list[bool], start: int) -> int:
    return sum(1 << i for i in range(32) if bits[start + i])


class OutputRecipe:
    def __init__(self, rid: int, names: list[str], frequency: float) -> None:
        self.id = rid
        self.names = names
        self.types = [rp.OUTPUT_TYPES.get(n, "NOT_FOUND") for n in names]
        self.getters = [_getter(n) for n in names]
        self.struct = rp.recipe_format(self.types)
        self.period = 1.0 / min(max(frequency, 1.0), MAX_FREQUENCY) if frequency > 0 else 1.0 / MAX_FREQUENCY

    @property
    def valid(self) -> bool:
        return self.struct is not None

    def pack(self, snap: Snapshot) -> bytes:
        values = [g(snap) for g in self.getters]  # type: ignore[misc]
        flat = rp.flatten(self.types, values)
        assert self.struct is not None
        return rp.pack(rp.DATA_PACKAGE, bytes([self.id]) + self.struct.pack(*flat))


class InputRecipe:
    def __init__(self, rid: int, names: list[str]) -> None:
        self.id = rid
        self.names = names
        self.types = [rp.INPUT_TYPES.get(n, "NOT_FOUND") for n in names]
        self.struct = rp.recipe_format(self.types)


class RTDEConnection:
    def __init__(self, sock: socket.socket, controller: Controller, stopping: Callable[[], bool]) -> None:
        self.sock = sock
        self.ctl = controller
        self.stopping = stopping
        self.buf = b""
        self.protocol = 1
        self.output: Optional[OutputRecipe] = None
        self.inputs: dict[int, InputRecipe] = {}
        self.next_output_id = 1  # output and input recipe ids are numbered separately (ur_rtde relies on it)
        self.next_input_id = 1
        self.started = False
        self.sent = 0

    def serve(self) -> None:
        self.sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        next_send = time.perf_counter()
        while not self.stopping():
            now = time.perf_counter()
            timeout = 0.1
            if self.started and self.output is not None:
                timeout = max(0.0, next_send - now)
            readable, _, _ = select.select([self.sock], [], [], timeout)
            if readable:
                data = self.sock.recv(65536)
                if not data:
                    return
                self.buf += data
                if not self._handle_packets():
                    return
            if self.started and self.output is not None and time.perf_counter() >= next_send:
                self.sock.sendall(self.output.pack(self.ctl.snapshot))
                self.sent += 1
                next_send += self.output.period
                now = time.perf_counter()
                if now - next_send > CATCH_UP:  # a long stall: resync instead of flooding the client
                    next_send = now

    def _handle_packets(self) -> bool:
        while len(self.buf) >= 3:
            size, ptype = rp.HEADER.unpack_from(self.buf)
            if size < 3:
                log.warning("RTDE: malformed package size %d, closing connection", size)
                return False
            if len(self.buf) < size:
                return True
            payload, self.buf = self.buf[3:size], self.buf[size:]
            try:
                self._handle(ptype, payload)
            except (struct.error, ValueError, IndexError, UnicodeError) as e:
                log.warning("RTDE: bad package type %r: %s", chr(ptype) if 32 <= ptype < 127 else ptype, e)
                self.sock.sendall(rp.text_message(f"bad package: {e}", "RTDE", 2))
        return True

    def _handle(self, ptype: int, payload: bytes) -> None:
        if ptype == rp.REQUEST_PROTOCOL_VERSION:
            (version,) = struct.unpack(">H", payload[:2])
            ok = version in (1, 2)
            if ok:
                self.protocol = version
            self.sock.sendall(rp.pack(ptype, bytes([1 if ok else 0])))
        elif ptype == rp.GET_URCONTROL_VERSION:
            self.sock.sendall(rp.pack(ptype, struct.pack(">IIII", *CONTROLLER_VERSION)))
        elif ptype == rp.CONTROL_PACKAGE_SETUP_OUTPUTS:
            if self.protocol >= 2:
                (freq,) = struct.unpack(">d", payload[:8])
                names = rp.parse_names(payload[8:])
            else:
                freq, names = MAX_FREQUENCY, rp.parse_names(payload)
            recipe = OutputRecipe(self.next_output_id, names, freq)
            if recipe.valid:
                self.output = recipe
                self.next_output_id += 1
                # A controller's own log tells which client streams what: the rate is what costs the controller.
                log.info("RTDE: output recipe %d, %d variables at %g Hz", recipe.id, len(names), 1.0 / recipe.period)
            else:
                log.warning("RTDE: output recipe with unknown variables: %s",
                            [n for n, t in zip(names, recipe.types) if t == "NOT_FOUND"])
            body = (bytes([recipe.id if recipe.valid else 0]) if self.protocol >= 2 else b"") + \
                ",".join(recipe.types).encode()
            self.sock.sendall(rp.pack(ptype, body))
        elif ptype == rp.CONTROL_PACKAGE_SETUP_INPUTS:
            names = rp.parse_names(payload)
            irec = InputRecipe(self.next_input_id, names)
            if irec.struct is not None:
                self.inputs[irec.id] = irec
                self.next_input_id += 1
            else:
                log.warning("RTDE: input recipe with unknown variables: %s",
                            [n for n, t in zip(names, irec.types) if t == "NOT_FOUND"])
            rid = irec.id if irec.struct is not None else 0
            self.sock.sendall(rp.pack(ptype, bytes([rid]) + ",".join(irec.types).encode()))
        elif ptype == rp.CONTROL_PACKAGE_START:
            self.started = True
            self.sock.sendall(rp.pack(ptype, b"\x01"))
        elif ptype == rp.CONTROL_PACKAGE_PAUSE:
            self.started = False
            self.sock.sendall(rp.pack(ptype, b"\x01"))
        elif ptype == rp.DATA_PACKAGE:
            rid = payload[0]
            recipe = self.inputs.get(rid)
            if recipe is None or recipe.struct is None:
                log.warning("RTDE: data package for unknown input recipe %d ignored", rid)
                return
            flat = recipe.struct.unpack(payload[1:1 + recipe.struct.size])
            values = rp.unflatten(recipe.types, flat)
            self.ctl.apply_inputs(dict(zip(recipe.names, values)))
        else:
            log.warning("RTDE: unknown package type %d ignored", ptype)
            self.sock.sendall(rp.text_message(f"unknown package type {ptype}", "RTDE", 2))


class RTDEServer(TcpServer):
    port = 30004

    def __init__(self, host: str, controller: Controller) -> None:
        super().__init__(host, self.port, "rtde")
        self.ctl = controller
        self.connections: list[RTDEConnection] = []

    def handle(self, sock: socket.socket) -> None:
        conn = RTDEConnection(sock, self.ctl, self.stopping)
        self.connections.append(conn)
        try:
            conn.serve()
        finally:
            self.connections.remove(conn)
