"""Wires one simulated cell together: the world, one emulated UR controller per arm (each with its RTDE, dashboard
and script servers on its own address), the loop that ticks them, and optionally cameras and ROS.

Which world is built and which devices are published where comes from the cell file (`CellOptions.devices`, see
sim/cell_file.py); the controllers' addresses from `CellOptions.hosts` (group -> host; sim/__main__.py resolves them).
"""
from __future__ import annotations

import logging
import threading
import time
from dataclasses import dataclass, field

from typing import Optional

from .cell_file import CellDevices
from .controller import Controller, WorldLoop
from .dashboard import DashboardServer
from .rtde_server import RTDEServer
from .safety import FaultBook, cell_faults
from .script_server import ScriptServer
from .tcp import TcpServer
from .world import World, restock_text

log = logging.getLogger("sim.cell")

SCRIPT_PORTS = (30001, 30002, 30003)


@dataclass
class CellOptions:
    host: str = "127.0.0.1"   # the controller's address when `hosts` does not name the arm's group
    hosts: Optional[dict[str, str]] = None  # group -> controller address, one per arm
    seed: int = 0
    speed: float = 1.0
    camera_size: tuple[int, int] = (640, 480)
    camera_rate: float = 15.0
    sensor_rate: float = 50.0
    cameras: bool = True
    ros: bool = True
    powered: bool = True
    program_start: float = 0.05   # s of sim time from a script upload or play until the program runs
    # The cell file's devices (parse_args reads the file); the default declares none, so nothing is published.
    devices: CellDevices = field(default_factory=CellDevices)


class Cell:
    def __init__(self, opts: CellOptions) -> None:
        self.opts = opts
        self.lock = threading.RLock()  # one physics client: every controller, the cameras and ROS share this lock
        self.world = World(seed=opts.seed, spec=opts.devices.world)
        table, fault_ids = cell_faults([(a.group, a.tool) for a in self.world.arms])
        self.faults = FaultBook(table)
        self.controllers: dict[str, Controller] = {}
        self.hosts: dict[str, str] = {}
        self.servers: list[TcpServer] = []
        for arm, ids in zip(self.world.arms, fault_ids):
            ctl = Controller(self.world, boot_powered=opts.powered, body=arm, lock=self.lock, faults=self.faults,
                             fault_ids=ids, program_start=opts.program_start)
            host = (opts.hosts or {}).get(arm.group, opts.host)
            self.controllers[arm.group], self.hosts[arm.group] = ctl, host
            self.servers += [RTDEServer(host, ctl), DashboardServer(host, ctl)]
            self.servers += [ScriptServer(host, port, ctl) for port in SCRIPT_PORTS]
        self.controller = next(iter(self.controllers.values()))  # the first arm's (the demo's only one)
        self.loop = WorldLoop(self.world, list(self.controllers.values()), self.lock)
        self.cameras = None
        self.ros = None

    def restock(self) -> tuple[bool, str]:
        """/sim/restock: the parts back where they lay at the start (sim/world.py World.restock)."""
        with self.lock:
            return True, restock_text(*self.world.restock())

    def trigger_fault(self, fault: str) -> tuple[bool, str]:
        """/sim/trigger_fault: `<group>.<fault>` for one arm; a plain fault name for every arm that has it (the door
        is the cell's; `reset` resets every arm)."""
        group, dot, name = fault.rpartition(".")
        if dot:
            ctl = self.controllers.get(group)
            if ctl is None:
                return False, f"unknown arm '{group}' (arms: {', '.join(self.controllers)})"
            return ctl.trigger_fault(name)
        targets = [c for c in self.controllers.values() if fault in c.fault_names]
        if not targets:
            names = dict.fromkeys(n for c in self.controllers.values() for n in c.fault_names)
            hint = f"; one arm: <group>.<fault>, groups {', '.join(self.controllers)}" if len(self.controllers) > 1 else ""
            return False, f"unknown fault '{fault}' ({', '.join(names)}{hint})"
        results = [c.trigger_fault(fault) for c in targets]
        return all(ok for ok, _ in results), results[0][1]

    def start(self) -> None:
        # The ports open last, once the loop runs: a client that connects as soon as they accept (ur_rtde gives its
        # control script 5 s to start) must not wait out the ROS start-up, which is slow on a busy host.
        # No video stream in the cell file: no render process at all.
        if self.opts.cameras and self.opts.devices.streams:
            from .cameras import CameraRig
            self.cameras = CameraRig(self.world, self.opts.camera_size, self.opts.camera_rate, self.opts.speed,
                                     views=self.opts.devices.views)
        if self.opts.ros:
            from .ros_bridge import RosBridge, ros_master_online
            if ros_master_online():
                try:
                    self.ros = RosBridge(self, self.opts.devices, self.opts.sensor_rate, self.opts.speed,
                                         camera_size=self.opts.camera_size)
                except ImportError as e:  # e.g. cell_msgs not built yet: still serve the UR ports
                    log.error("ROS messages not importable (%s): build ros_backend; running without ROS", e)
                else:
                    self.ros.start()
            else:
                log.warning("ROS master not reachable: running without ROS")
        if self.cameras is not None:
            self.cameras.start(self.controller, self.ros.publish_image if self.ros else None,
                               self.ros.watched_views if self.ros else None, self.ros)
        self._t0 = (time.monotonic(), self.loop.sim_time)
        self.loop.start(self.opts.speed)
        for s in self.servers:
            s.start()

    def stats(self) -> str:
        """One line of performance figures (the bench parses it): real-time factor, camera frames, render ms."""
        wall = time.monotonic() - self._t0[0]
        rtf = (self.loop.sim_time - self._t0[1]) / wall if wall > 0 else 0.0
        line = f"stats: wall={wall:.2f}s sim={self.loop.sim_time:.2f}s rtf={rtf:.3f}"
        if self.cameras is not None and self.cameras.render_ms:
            ms = sorted(self.cameras.render_ms)
            line += (f" camera_cycles={self.cameras.frames} camera_hz={self.cameras.frames / wall:.2f}"
                     f" render_ms_mean={sum(ms) / len(ms):.1f} render_ms_p95={ms[int(len(ms) * 0.95)]:.1f}"
                     f" renderer={self.cameras.renderer}")
        return line

    def stop(self) -> None:
        if hasattr(self, "_t0"):
            log.info(self.stats())
        t0 = time.monotonic()
        for s in self.servers:
            s.signal_stop()
        if self.cameras is not None:
            self.cameras.signal_stop()
        for s in self.servers:
            s.stop()
        t1 = time.monotonic()
        self.loop.stop()
        t2 = time.monotonic()
        # Unregistering from the ROS master takes several XML-RPC round trips: overlap it with the cameras.
        ros_stop = threading.Thread(target=self.ros.stop, daemon=True) if self.ros is not None else None
        if ros_stop is not None:
            ros_stop.start()
        if self.cameras is not None:
            self.cameras.stop()
        t3 = time.monotonic()
        if ros_stop is not None:
            ros_stop.join(1.0)
        t4 = time.monotonic()
        self.world.close()
        log.debug("stop took: servers %.2fs, controller %.2fs, cameras %.2fs, ros %.2fs",
                  t1 - t0, t2 - t1, t3 - t2, t4 - t3)
