#!/usr/bin/env python3
"""Simulator benchmark (loopback only, stops by itself).

Starts `python -m sim` with both cameras on (640x480 @ 15 Hz by default), connects ur_rtde's
RTDEReceiveInterface (what the ROS driver uses) plus a raw RTDE client asking for 500 Hz, and prints:
  - real-time factor (controller time / wall time) with both cameras rendering,
  - ms per rendered camera frame (render + JPEG) and camera cycles per second,
  - RTDE receive rate achieved (e-Series profile: 500 Hz).
Usage: python bench/sim_bench.py [--seconds 15] [--host 127.0.0.29] [--camera-size 640x480] [--camera-rate 15]
BENCH_QUICK=1 (npm run bench -- --quick) makes the default 4 s, counted once the cameras render (the full run
starts counting 2 s after the RTDE port opens); camera cycles per second is the sim's whole-run average,
start-up included, so it reads lower in the quick run.
"""
from __future__ import annotations

import argparse
import os
import re
import signal
import socket
import struct
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def packet(ptype: str, payload: bytes = b"") -> bytes:
    return struct.pack(">HB", 3 + len(payload), ord(ptype)) + payload


def read_exact(sock: socket.socket, n: int) -> bytes:
    buf = b""
    while len(buf) < n:
        chunk = sock.recv(n - len(buf))
        if not chunk:
            raise ConnectionError("sim closed the RTDE connection")
        buf += chunk
    return buf


def read_packet(sock: socket.socket) -> tuple[str, bytes]:
    size, ptype = struct.unpack(">HB", read_exact(sock, 3))
    return chr(ptype), read_exact(sock, size - 3)


def wait_port(host: str, port: int, timeout: float, proc: subprocess.Popen) -> None:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if proc.poll() is not None:
            raise SystemExit("sim exited during start-up")
        try:
            socket.create_connection((host, port), timeout=0.2).close()
            return
        except OSError:
            time.sleep(0.1)
    raise SystemExit(f"sim did not open {host}:{port}")


def main() -> int:
    ap = argparse.ArgumentParser()
    quick = os.environ.get("BENCH_QUICK") == "1"
    ap.add_argument("--seconds", type=float, default=4.0 if quick else 15.0)
    # Not 127.0.0.9, the UR_HOST of e2e/lib/stack.js's stacks: an e2e run's sim there held the ports, and the bench
    # measured that sim (or failed when it went away).
    ap.add_argument("--host", default="127.0.0.29")
    ap.add_argument("--camera-size", default="640x480")
    ap.add_argument("--camera-rate", default="15")
    a = ap.parse_args()
    if not a.host.startswith("127."):
        raise SystemExit("loopback addresses only")
    log = tempfile.NamedTemporaryFile("w+", prefix="sim-bench-", suffix=".log", delete=False)
    env = dict(os.environ, PYTHONPATH=f"{ROOT}:{os.environ.get('PYTHONPATH', '')}")
    proc = subprocess.Popen([sys.executable, "-m", "sim", "--host", a.host, "--no-ros", "--camera-size",
                             a.camera_size, "--camera-rate", a.camera_rate], cwd=ROOT, env=env,
                            stdout=log, stderr=subprocess.STDOUT, start_new_session=True)
    try:
        wait_port(a.host, 30004, 30, proc)
        time.sleep(0.3)
        if proc.poll() is not None:  # another process holds the ports: what answered is not this sim
            raise SystemExit(f"sim exited during start-up: {Path(log.name).read_text()[-300:]}")
        import rtde_receive  # the client the product uses; it reads at 500 Hz from an e-Series controller
        receiver = rtde_receive.RTDEReceiveInterface(a.host)
        if quick:  # the short window must see the cameras render: their process takes seconds to start
            deadline = time.monotonic() + 60
            while "cameras: " not in Path(log.name).read_text() and time.monotonic() < deadline:
                if proc.poll() is not None:
                    raise SystemExit("sim exited")
                time.sleep(0.2)
        time.sleep(2.0)  # let the camera process warm up (first EGL frames are slow)
        s = socket.create_connection((a.host, 30004), timeout=5)
        s.sendall(packet("V", struct.pack(">H", 2)))
        read_packet(s)
        s.sendall(packet("O", struct.pack(">d", 500.0) + b"timestamp,actual_q,actual_TCP_pose,robot_mode,"))
        read_packet(s)
        s.sendall(packet("S"))
        read_packet(s)
        # Count only after start-up: packages queued in the socket while we were busy would inflate the rate.
        n, first, last = 0, None, None
        t_end = time.monotonic() + a.seconds
        while time.monotonic() < t_end:
            kind, body = read_packet(s)
            if kind != "U":
                continue
            ts = struct.unpack(">d", body[1:9])[0]
            now = time.monotonic()
            if first is None:
                first = (now, ts)
            last = (now, ts)
            n += 1
        s.close()
        ur_rtde_ts = receiver.getTimestamp()
        receiver.disconnect()
    finally:
        proc.send_signal(signal.SIGINT)
        try:
            proc.wait(10)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)
    assert first and last
    wall = last[0] - first[0]
    rate = (n - 1) / wall
    rtf = (last[1] - first[1]) / wall
    out = Path(log.name).read_text()
    stats = re.search(r"stats: .*", out)
    fields = dict(re.findall(r"(\w+)=([\w.]+)", stats.group(0))) if stats else {}
    print(f"window                      : {wall:.1f} s, cameras {a.camera_size} @ {a.camera_rate} Hz (both on){', quick' if quick else ''}")
    print(f"real-time factor            : {rtf:.3f}  (whole run: {fields.get('rtf', '?')})")
    print(f"RTDE receive rate (500 Hz)  : {rate:.1f} Hz  ({n} packages; ur_rtde client saw t={ur_rtde_ts:.2f} s)")
    print(f"ms per rendered frame       : mean {fields.get('render_ms_mean', '?')} ms, "
          f"p95 {fields.get('render_ms_p95', '?')} ms (renderer {fields.get('renderer', '?')})")
    print(f"camera cycles per second    : {fields.get('camera_hz', '?')} (each cycle = 1 frame per camera)")
    print(f"sim log                     : {log.name}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
