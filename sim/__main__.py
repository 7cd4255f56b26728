"""CLI: python -m sim [--host H | --hosts group=host,...] [--cell FILE] [...]  runs the simulated cell until
SIGINT/SIGTERM.

The cell file (--cell, else CELL_CONFIG, else config/demo-cell.yaml) says which world is built (`simulation:`, else
the demo world) and on which topics the simulated devices publish; an unreadable or unusable file ends the start with
a one-line error and exit code 2. Each arm's controller listens on its motion group's host (arm_hosts below).
"""
from __future__ import annotations

import argparse
import logging
import os
import signal
import sys
import threading
from typing import Any, Mapping, Optional

from .cell import Cell, CellOptions
from .cell_file import CellDevices, CellFileError, default_cell_path, devices_from, read_cell_file
from .priority import claim_priority
from .hosts import parse_host_list, resolve_hosts


def parse_size(text: str) -> tuple[int, int]:
    w, _, h = text.lower().partition("x")
    try:
        size = (int(w), int(h))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected WIDTHxHEIGHT, got {text!r}")
    if min(size) < 16 or max(size) > 4096:
        raise argparse.ArgumentTypeError("camera size out of range")
    return size


def arm_hosts(doc: Mapping[str, Any], devices: CellDevices, environ: Mapping[str, str], host: Optional[str] = None,
              hosts: Optional[str] = None) -> dict[str, str]:
    """group -> address of each simulated arm's controller.

    One arm and --host: that host. Otherwise the shared rule (sim/hosts.py: UR_HOSTS, else manual.groups[].host,
    else UR_HOST, else 127.0.0.1), --host standing in for UR_HOST; --hosts overrides it per group (a motion group
    of the cell that is no simulated arm, e.g. a second group of one arm, is ignored there). Two arms on one address
    (its UR ports are fixed) or --hosts naming neither an arm nor a motion group: ValueError.
    """
    groups = [a.group for a in devices.world.arms]
    given = parse_host_list(hosts or "", "--hosts")
    known = set(groups) | set(resolve_hosts(doc.get("manual"), {}))
    unknown = [g for g in given if g not in known]
    if unknown:
        raise ValueError(f"--hosts: no simulated arm {unknown[0]!r} (the arms: {', '.join(groups)})")
    if len(groups) == 1 and host and groups[0] not in given:
        return {groups[0]: host}
    env = dict(environ)
    if host:
        env["UR_HOST"] = host
    resolved = resolve_hosts(doc.get("manual"), env)
    fallback = resolve_hosts({"groups": [{"name": "_"}]}, env)["_"]  # an arm of a cell without manual groups
    out = {g: given.get(g) or resolved.get(g) or fallback for g in groups}
    seen: dict[str, str] = {}
    for g, h in out.items():
        if h in seen:
            raise ValueError(f"arms {seen[h]} and {g} both on {h}: each arm's controller needs its own address "
                             f"(manual.groups[].host, UR_HOSTS or --hosts)")
        seen[h] = g
    return out


def parse_args(argv: Optional[list[str]] = None) -> CellOptions:
    ap = argparse.ArgumentParser(prog="python -m sim", description="Simulated UR5 cell + UR controller emulator")
    ap.add_argument("--host", default=None,
                    help="address to serve RTDE/dashboard/script ports on (one arm); with several arms the address "
                         "of groups without their own (default: the cell file's manual.groups[].host, UR_HOST, "
                         "127.0.0.1)")
    ap.add_argument("--hosts", default=None, metavar="GROUP=HOST,...",
                    help="each arm's address by motion group (overrides UR_HOSTS and the cell file)")
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
    ap.add_argument("--program-start", type=float, default=0.05, metavar="S",
                    help="seconds from a script upload or play until the program runs (a real controller compiles "
                         "it first; tests use a slow one)")
    ap.add_argument("--log-level", default="INFO")
    a = ap.parse_args(argv)
    if a.speed <= 0 or a.camera_rate <= 0 or a.sensor_rate <= 0:
        ap.error("--speed, --camera-rate and --sensor-rate must be positive")
    if a.program_start < 0:
        ap.error("--program-start must not be negative")
    path = a.cell or default_cell_path()
    try:
        doc = read_cell_file(path)
        devices = devices_from(doc, path)
        hosts = arm_hosts(doc, devices, os.environ, a.host, a.hosts)
    except (CellFileError, ValueError) as e:
        # A configuration mistake, not a crash: one clear line, no traceback, no usage text.
        ap.exit(2, f"{ap.prog}: {e}\n")
    logging.basicConfig(level=a.log_level.upper(), format="%(asctime)s %(name)s %(levelname)s %(message)s")
    logging.getLogger("sim").info("cell file %s: wrench on %s, tactile on %s, %d camera stream(s)", devices.path,
                                  ", ".join(devices.wrench_topics) or "-", ", ".join(devices.tactile_topics) or "-",
                                  len(devices.streams))
    logging.getLogger("sim").info("arms: %s", ", ".join(
        f"{g} ({devices.world.arm(g).tool.kind}) on {h}" for g, h in hosts.items()))
    return CellOptions(host=next(iter(hosts.values())), hosts=hosts, seed=a.seed, speed=a.speed, camera_size=a.camera_size,
                       camera_rate=a.camera_rate, sensor_rate=a.sensor_rate, cameras=not a.no_cameras,
                       ros=not a.no_ros, powered=not a.power_off, devices=devices,
                       program_start=a.program_start)


def simulation_kind(argv: Optional[list[str]]) -> Optional[str]:
    """The cell file's simulation.kind (None: the UR cell, or a file parse_args will report on)."""
    ap = argparse.ArgumentParser(add_help=False)
    ap.add_argument("--cell", default=None)
    known, _ = ap.parse_known_args(argv)
    try:
        doc = read_cell_file(known.cell or default_cell_path())
    except CellFileError:
        return None
    section = doc.get("simulation") if isinstance(doc, dict) else None
    return section.get("kind") if isinstance(section, dict) else None


def main(argv: Optional[list[str]] = None) -> int:
    if simulation_kind(argv) == "ros_control":
        # A ros_control robot driver's ROS interface (sim/ros_control), not a UR controller.
        from .ros_control.main import main as ros_control_main
        return ros_control_main(argv)
    opts = parse_args(argv)
    logging.getLogger("sim").info(claim_priority("sim (the arms' controllers)"))
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
    logging.getLogger("sim").info("cell running on %s (speed %.3gx); Ctrl-C to stop",
                                  ", ".join(sorted(set((opts.hosts or {}).values()))) or opts.host, opts.speed)
    while not done.wait(0.2):
        pass
    # A stop is bounded, as a controller's power-off is: CI once saw this process take 10 s to exit on SIGTERM (a
    # thread that never ended). Past STOP_DEADLINE_S the threads still alive are logged, then the process exits.
    deadline = threading.Timer(STOP_DEADLINE_S, _exit_stuck)
    deadline.daemon = True
    deadline.start()
    cell.stop()
    logging.getLogger("sim").info("stopped")
    return 0


STOP_DEADLINE_S = 1.8   # the tests expect an exit within 2 s of SIGTERM


def _exit_stuck() -> None:
    alive = [t.name for t in threading.enumerate() if t is not threading.current_thread() and t.is_alive()]
    logging.getLogger("sim").error("stop took over %.1f s; still running: %s; exiting", STOP_DEADLINE_S,
                                   ", ".join(alive) or "none")
    logging.shutdown()
    os._exit(1)


if __name__ == "__main__":
    sys.exit(main())
