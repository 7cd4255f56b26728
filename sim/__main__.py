"""CLI: python -m sim --host <UR_HOST> [--cell FILE] [...]  runs the simulated cell until SIGINT/SIGTERM.

The cell file (--cell, else CELL_CONFIG, else config/demo-cell.yaml) says on which topics the simulated
devices publish; an unreadable or unusable file ends the start with a one-line error and exit code 2.
"""
from __future__ import annotations

import argparse
import logging
import signal
import sys
import threading
from typing import Optional

from .cell import Cell, CellOptions
from .cell_file import CellFileError, default_cell_path, load_devices


def parse_size(text: str) -> tuple[int, int]:
    w, _, h = text.lower().partition("x")
    try:
        size = (int(w), int(h))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected WIDTHxHEIGHT, got {text!r}")
    if min(size) < 16 or max(size) > 4096:
        raise argparse.ArgumentTypeError("camera size out of range")
    return size


def parse_args(argv: Optional[list[str]] = None) -> CellOptions:
    ap = argparse.ArgumentParser(prog="python -m sim", description="Simulated UR5 cell + UR controller emulator")
    ap.add_argument("--host", default="127.0.0.1", help="address to serve RTDE/dashboard/script ports on")
    ap.add_argument("--cell", default=None, metavar="FILE",
                    help="cell file naming the device topics (default: $CELL_CONFIG, else config/demo-cell.yaml)")
    ap.add_argument("--seed", type=int, default=0, help="seed for part placement (deterministic physics)")
    ap.add_argument("--speed", type=float, default=1.0, help="real-time factor (e.g. 4 for tests)")
    ap.add_argument("--camera-size", type=parse_size, default=(640, 480))
    ap.add_argument("--camera-rate", type=float, default=15.0, help="frames per second per camera")
    ap.add_argument("--sensor-rate", type=float, default=50.0, help="F/T and tactile rate (Hz)")
    ap.add_argument("--no-cameras", action="store_true")
    ap.add_argument("--no-ros", action="store_true")
    ap.add_argument("--power-off", action="store_true",
                    help="boot like a real arm: powered off with brakes on (power on + brake release needed)")
    ap.add_argument("--log-level", default="INFO")
    a = ap.parse_args(argv)
    if a.speed <= 0 or a.camera_rate <= 0 or a.sensor_rate <= 0:
        ap.error("--speed, --camera-rate and --sensor-rate must be positive")
    try:
        devices = load_devices(a.cell or default_cell_path())
    except CellFileError as e:
        # A configuration mistake, not a crash: one clear line, no traceback, no usage text.
        ap.exit(2, f"{ap.prog}: {e}\n")
    logging.basicConfig(level=a.log_level.upper(), format="%(asctime)s %(name)s %(levelname)s %(message)s")
    logging.getLogger("sim").info("cell file %s: wrench on %s, tactile on %s, %d camera stream(s)", devices.path,
                                  ", ".join(devices.wrench_topics) or "-", ", ".join(devices.tactile_topics) or "-",
                                  len(devices.streams))
    return CellOptions(host=a.host, seed=a.seed, speed=a.speed, camera_size=a.camera_size,
                       camera_rate=a.camera_rate, sensor_rate=a.sensor_rate, cameras=not a.no_cameras,
                       ros=not a.no_ros, powered=not a.power_off, devices=devices)


def main(argv: Optional[list[str]] = None) -> int:
    opts = parse_args(argv)
    # Many small periodic threads (500 Hz control loop, RTDE streams): hand the GIL over sooner than 5 ms.
    sys.setswitchinterval(0.0005)
    done = threading.Event()
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, lambda *_: done.set())
    cell = Cell(opts)
    try:
        cell.start()
    except OSError as e:
        logging.getLogger("sim").error("cannot start: %s", e)
        cell.stop()
        return 1
    logging.getLogger("sim").info("cell running on %s (speed %.3gx); Ctrl-C to stop", opts.host, opts.speed)
    while not done.wait(0.2):
        pass
    cell.stop()
    logging.getLogger("sim").info("stopped")
    return 0


if __name__ == "__main__":
    sys.exit(main())
