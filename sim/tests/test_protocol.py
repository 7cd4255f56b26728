"""Raw-socket checks: RTDE handshake details, refusals of unknown things, and surviving bad clients."""
from __future__ import annotations

import os
import signal
import socket
import struct
import time

import pytest
import rtde_receive

from conftest import wait_for

SIM_HOST = "127.0.0.15"
SIM_ARGS = ["--no-cameras", "--no-ros"]


def rtde_packet(ptype: str, payload: bytes = b"") -> bytes:
    return struct.pack(">HB", 3 + len(payload), ord(ptype)) + payload


def read_packet(sock: socket.socket) -> tuple[str, bytes]:
    head = _read(sock, 3)
    size, ptype = struct.unpack(">HB", head)
    return chr(ptype), _read(sock, size - 3)


def _read(sock: socket.socket, n: int) -> bytes:
    buf = b""
    while len(buf) < n:
        chunk = sock.recv(n - len(buf))
        if not chunk:
            raise ConnectionError("closed")
        buf += chunk
    return buf


@pytest.fixture
def rtde(module_sim):
    s = socket.create_connection((SIM_HOST, 30004), timeout=3)
    yield s
    s.close()


def test_handshake_version_and_recipe_types(rtde):
    rtde.sendall(rtde_packet("V", struct.pack(">H", 2)))
    assert read_packet(rtde) == ("V", b"\x01")
    rtde.sendall(rtde_packet("V", struct.pack(">H", 9)))
    assert read_packet(rtde) == ("V", b"\x00")  # unsupported protocol version refused
    rtde.sendall(rtde_packet("v"))
    kind, body = read_packet(rtde)
    major, minor, bugfix, build = struct.unpack(">IIII", body)
    assert kind == "v" and major == 5  # e-Series: clients stream at 500 Hz
    rtde.sendall(rtde_packet("O", struct.pack(">d", 125.0) + b"timestamp,actual_q,robot_mode,no_such_thing,"))
    kind, body = read_packet(rtde)
    assert kind == "O" and body[0] == 0  # a recipe with an unknown variable is refused
    assert body[1:].decode() == "DOUBLE,VECTOR6D,INT32,NOT_FOUND"
    rtde.sendall(rtde_packet("O", struct.pack(">d", 125.0) + b"timestamp,actual_q,robot_mode,"))
    kind, body = read_packet(rtde)
    assert kind == "O" and body[0] == 1 and body[1:].decode() == "DOUBLE,VECTOR6D,INT32"
    rtde.sendall(rtde_packet("I", b"input_int_register_30,standard_digital_output,"))
    kind, body = read_packet(rtde)
    assert kind == "I" and body[0] == 1 and body[1:].decode() == "INT32,UINT8"
    rtde.sendall(rtde_packet("S"))
    assert read_packet(rtde) == ("S", b"\x01")
    stamps = []
    while len(stamps) < 30:
        kind, body = read_packet(rtde)
        if kind == "U":
            rid, ts = struct.unpack(">Bd", body[:9])
            assert rid == 1 and len(body) == 1 + 8 + 48 + 4
            stamps.append((time.monotonic(), ts))
    rate = (len(stamps) - 1) / (stamps[-1][0] - stamps[0][0])
    assert 100 < rate < 150, f"asked for 125 Hz, got {rate:.0f} Hz"
    assert stamps[-1][1] > stamps[0][1]  # controller time advances
    rtde.sendall(rtde_packet("P"))
    wait_for(lambda: read_packet(rtde) == ("P", b"\x01"), 3, interval=0, what="pause reply")


def test_unknown_package_type_answered_with_text_message(rtde):
    rtde.sendall(rtde_packet("Z", b"junk"))
    kind, body = read_packet(rtde)
    assert kind == "M"
    assert b"unknown package type" in body


def test_garbage_on_every_port_does_not_take_the_server_down(module_sim):
    junk = os.urandom(4096)
    for port in (30004, 29999, 30001, 30002, 30003):
        for payload in (junk, b"\x00\x01", b"\xff" * 70000, "def x():\n  popup(1)\nend\n".encode()):
            with socket.create_connection((SIM_HOST, port), timeout=3) as s:
                try:
                    s.sendall(payload)
                except OSError:
                    pass  # the server may close on us: that is fine
    with socket.create_connection((SIM_HOST, 29999), timeout=3) as s:
        f = s.makefile("rw")
        f.readline()
        f.write("robotmode\n")
        f.flush()
        assert f.readline().strip() == "Robotmode: RUNNING"
    r = rtde_receive.RTDEReceiveInterface(SIM_HOST)
    assert r.getRobotMode() == 7
    r.disconnect()
    assert module_sim.proc.poll() is None
    assert "Traceback" not in module_sim.output()


def test_sigint_exits_cleanly_within_2s(start_sim):
    sim = start_sim("127.0.0.16", "--no-ros")  # with the camera process running
    took = sim.stop(signal.SIGINT)
    assert sim.proc.returncode == 0
    assert took < 2.0
    assert "stopped" in sim.output()


def test_runs_without_ros_when_no_master(start_sim):
    sim = start_sim("127.0.0.17", "--no-cameras")  # ROS enabled, but the master URI points nowhere
    r = rtde_receive.RTDEReceiveInterface("127.0.0.17")
    assert r.getRobotMode() == 7
    r.disconnect()
    assert "running without ROS" in sim.output()
