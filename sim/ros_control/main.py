"""CLI of the ros_control cell: `python -m sim --cell FILE` when the file's simulation.kind is ros_control
(sim/__main__.py dispatches here). Runs until SIGINT/SIGTERM; an unusable cell file exits 2 with one line."""
from __future__ import annotations

import argparse
import logging
import signal
import sys
import threading
from typing import Optional

from ..cell_file import CellFileError, default_cell_path, devices_from, read_cell_file
from ..priority import claim_priority
from .cell import RosControlCell, RosControlOptions


def parse_args(argv: Optional[list[str]] = None) -> RosControlOptions:
    from ..__main__ import parse_size
    ap = argparse.ArgumentParser(prog="python -m sim",
                                 description="Simulated ros_control robot cell (a KUKA LBR iiwa driver's ROS interface)")
    ap.add_argument("--cell", default=None, metavar="FILE",
                    help="cell file (default: $CELL_CONFIG, else config/demo-cell.yaml)")
    # The UR cell's address options mean nothing here (a ros_control driver has no controller ports): accepted so
    # the same command line starts either kind of cell.
    ap.add_argument("--host", default=None, help=argparse.SUPPRESS)
    ap.add_argument("--hosts", default=None, help=argparse.SUPPRESS)
    ap.add_argument("--power-off", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument("--seed", type=int, default=0, help="seed for part placement (deterministic physics)")
    ap.add_argument("--speed", type=float, default=1.0, help="real-time factor (physics and trajectory time)")
    ap.add_argument("--camera-size", type=parse_size, default=(640, 480))
    ap.add_argument("--camera-rate", type=float, default=15.0, help="frames per second per camera")
    ap.add_argument("--sensor-rate", type=float, default=50.0, help="wrist F/T rate (Hz)")
    ap.add_argument("--no-cameras", action="store_true")
    ap.add_argument("--no-ros", action="store_true")
    ap.add_argument("--log-level", default="INFO")
    a = ap.parse_args(argv)
    if a.speed <= 0 or a.camera_rate <= 0 or a.sensor_rate <= 0:
        ap.error("--speed, --camera-rate and --sensor-rate must be positive")
    path = a.cell or default_cell_path()
    try:
        devices = devices_from(read_cell_file(path), path)
    except CellFileError as e:
        ap.exit(2, f"{ap.prog}: {e}\n")
    logging.basicConfig(level=a.log_level.upper(), format="%(asctime)s %(name)s %(levelname)s %(message)s")
    for r in devices.world.robots:
        logging.getLogger("sim").info("ros_control arm %s: %s (%s), controller %s", r.group, r.model_name,
                                      ", ".join(r.model.joint_names), r.ros.controller)
    return RosControlOptions(seed=a.seed, speed=a.speed, camera_size=a.camera_size, camera_rate=a.camera_rate,
                             sensor_rate=a.sensor_rate, cameras=not a.no_cameras, ros=not a.no_ros, devices=devices)


def main(argv: Optional[list[str]] = None) -> int:
    opts = parse_args(argv)
    logging.getLogger("sim").info(claim_priority("sim (the arm's ros_control driver)"))
    sys.setswitchinterval(0.0005)  # a 500 Hz loop among publisher threads: hand the GIL over sooner than 5 ms
    done = threading.Event()
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, lambda *_: done.set())
    cell = RosControlCell(opts)
    cell.start()
    logging.getLogger("sim").info("ros_control cell running (speed %.3gx); Ctrl-C to stop", opts.speed)
    while not done.wait(0.2):
        pass
    cell.stop()
    logging.getLogger("sim").info("stopped")
    return 0
