"""Wires the ros_control cell together: the world, one trajectory controller per arm, the 500 Hz loop, the faults,
optionally cameras and ROS (sim/ros_bridge.py for the device topics, driver.py for each arm's driver interface).

The loop (real time x speed, sim/pacing.py): per tick, under the one lock, every arm's controller samples its
trajectory at the sim time and checks its tolerances against the arm's state, the arm is commanded the desired
position and velocity, the suction takes a part under a cup, then the physics steps once.
"""
from __future__ import annotations

import logging
import queue
import threading
import time
from dataclasses import dataclass, field
from typing import Optional

import numpy as np

from ..cell_file import CellDevices
from ..safety import FaultBook
from ..world import DT, restock_text
from .spec import RosControlArm, RosControlWorld
from .trajectory import Defaults, GoalEvent, TrajectoryController
from .world import IiwaArm, IiwaWorld

MAX_CATCH_UP_S = 0.1   # sim seconds a stalled loop catches up (50 cycles at 500 Hz); a longer stall is lost

log = logging.getLogger("sim.ros_control")

FAULTS = {
    "collision": ("Collision: the arm is blocked and cannot follow its trajectory", 2),
    "vacuum_fault": ("Vacuum fault: the suction does not respond to commands", 2),
}


@dataclass
class Snapshot:
    """The arm's last state, read by the publishers without the lock (replaced whole each tick)."""
    t: float
    q: np.ndarray
    qd: np.ndarray
    effort: np.ndarray
    ft_raw: np.ndarray
    holding: bool = False


@dataclass
class RosControlOptions:
    seed: int = 0
    speed: float = 1.0
    camera_size: tuple[int, int] = (640, 480)
    camera_rate: float = 15.0
    sensor_rate: float = 50.0
    cameras: bool = True
    ros: bool = True
    devices: CellDevices = field(default_factory=CellDevices)


class ArmRuntime:
    """One arm: its body in the world, its trajectory controller, its fault ids and its last state."""

    def __init__(self, body: IiwaArm, spec: RosControlArm, fault_ids: dict[str, str]) -> None:
        self.body, self.spec, self.fault_ids = body, spec, fault_ids
        self.group = spec.group
        self.ctl = TrajectoryController(spec.model.joint_names, Defaults())
        self.ctl.hold(0.0, spec.start_joints)
        q, qd, effort, ft = body.read()
        self.snapshot = Snapshot(0.0, q, qd, effort, ft)
        self.events: "queue.Queue[GoalEvent]" = queue.Queue()  # goals the loop ended, for the driver's results


class RosControlCell:
    def __init__(self, opts: RosControlOptions) -> None:
        self.opts = opts
        spec = opts.devices.world
        assert isinstance(spec, RosControlWorld)
        self.lock = threading.RLock()  # the physics client, the controllers: the loop, ROS and the cameras share it
        self.world = IiwaWorld(seed=opts.seed, spec=spec)
        several = len(spec.robots) > 1
        table: dict[str, tuple[str, int]] = {}
        self.controllers: dict[str, ArmRuntime] = {}
        for body, robot in zip(self.world.arms, spec.robots):
            ids = {name: (f"{robot.group}.{name}" if several else name) for name in FAULTS}
            for name, fid in ids.items():
                text, sev = FAULTS[name]
                table[fid] = (f"Robot {robot.group}: {text}" if several else text, sev)
            self.controllers[robot.group] = ArmRuntime(body, robot, ids)
        self.faults = FaultBook(table)
        self.sim_time = 0.0
        self._stop = threading.Event()
        self._thread: Optional[threading.Thread] = None
        self.cameras = None
        self.ros = None
        self.drivers: list = []

    # ---- the loop ---------------------------------------------------------------------------------------
    def tick(self) -> None:
        """One control cycle and physics step (callers hold the lock or own the world)."""
        t = self.sim_time
        for rt in self.controllers.values():
            q, qd, effort, ft = rt.body.read()
            q_des, qd_des, events = rt.ctl.update(t, q, qd)
            rt.body.command_arm(q_des, qd_des)
            rt.body.tick_tool()
            rt.snapshot = Snapshot(t, q, qd, effort, ft, rt.body.held is not None)
            for ev in events:
                rt.events.put(ev)
        self.world.step()
        self.sim_time = t + DT

    def _loop(self) -> None:
        """Keeps the controller's clock on the wall clock (x speed), as a real controller's is: after a stall it
        catches up with a burst of cycles (at most MAX_CATCH_UP_S worth; a longer stall is lost). Why: commands are
        stamped on the sender's wall clock (a streamed jog models the controller's setpoint on it), and a controller
        clock that fell behind would make a stamped trajectory's setpoint run fast for a moment."""
        start_wall, start_sim = time.perf_counter(), self.sim_time
        while not self._stop.is_set():
            due = start_sim + (time.perf_counter() - start_wall) * self.opts.speed
            if due - self.sim_time > MAX_CATCH_UP_S:  # a long stall: lose that time rather than burst through it
                start_wall, start_sim = time.perf_counter(), self.sim_time
                due = self.sim_time
            while self.sim_time < due and not self._stop.is_set():
                with self.lock:
                    self.tick()
            # until the wall clock reaches the controller's (one cycle ahead now)
            self._stop.wait(max(0.0, (self.sim_time - start_sim) / self.opts.speed - (time.perf_counter() - start_wall)))

    # ---- faults -----------------------------------------------------------------------------------------
    def restock(self) -> tuple[bool, str]:
        """/sim/restock: the parts back where they lay at the start (sim/world.py World.restock)."""
        with self.lock:
            return True, restock_text(*self.world.restock())

    def trigger_fault(self, fault: str) -> tuple[bool, str]:
        """/sim/trigger_fault: collision, vacuum_fault (every arm; `<group>.<fault>` for one), reset (every arm)."""
        group, dot, name = fault.rpartition(".")
        if dot and group not in self.controllers:
            return False, f"unknown arm '{group}' (arms: {', '.join(self.controllers)})"
        targets = [self.controllers[group]] if dot else list(self.controllers.values())
        if name not in (*FAULTS, "reset"):
            return False, f"unknown fault '{fault}' ({', '.join((*FAULTS, 'reset'))})"
        with self.lock:
            for rt in targets:
                if name == "collision":
                    rt.body.blocked = rt.snapshot.q.copy()
                elif name == "vacuum_fault":
                    rt.body.gripper_frozen = True
                else:
                    self._reset(rt)
        for rt in targets:
            for fname, fid in rt.fault_ids.items():
                if name == "reset" or fname == name:
                    self.faults.set(fid, name != "reset")
        return True, f"{fault}: done"

    def _reset(self, rt: ArmRuntime) -> None:
        rt.body.gripper_frozen = False
        if rt.body.blocked is not None:
            # The arm comes free where it stands: its controller restarts holding there, so it does not jump to
            # where the trajectory has got to meanwhile. A goal still running (no path tolerance) ends.
            rt.body.blocked = None
            ev = rt.ctl.abort(self.sim_time, rt.snapshot.q, "the arm was blocked (collision) until the reset")
            if ev is not None:
                rt.events.put(ev)

    # ---- start / stop -----------------------------------------------------------------------------------
    def start(self) -> None:
        devices = self.opts.devices
        if self.opts.cameras and devices.streams:
            from ..cameras import CameraRig
            self.cameras = CameraRig(self.world, self.opts.camera_size, self.opts.camera_rate, self.opts.speed,
                                     views=devices.views)
        if self.opts.ros:
            from ..ros_bridge import RosBridge, ros_master_online
            if ros_master_online():
                try:
                    self.ros = RosBridge(self, devices, self.opts.sensor_rate, self.opts.speed)
                    from .driver import ArmDriver
                    self.drivers = [ArmDriver(self, rt) for rt in self.controllers.values()]
                except ImportError as e:  # e.g. control_msgs / cell_msgs not built: physics still runs
                    log.error("ROS messages not importable (%s): build ros_backend; running without ROS", e)
                    self.ros, self.drivers = None, []
                else:
                    self.ros.start()
                    for d in self.drivers:
                        d.start()
            else:
                log.warning("ROS master not reachable: running without ROS")
        if self.cameras is not None:
            self.cameras.start(self, self.ros.publish_image if self.ros else None,
                               self.ros.watched_views if self.ros else None, self.ros)
        self._t0 = (time.monotonic(), self.sim_time)
        self._thread = threading.Thread(target=self._loop, name="ros-control-loop", daemon=True)
        self._thread.start()

    def ft_frame(self, group: str) -> str:
        """The wrist wrench's frame: the URDF's F/T link (the flange)."""
        from .model import ft_link
        return ft_link(self.controllers[group].spec.model)

    def stop(self) -> None:
        if hasattr(self, "_t0"):
            wall = time.monotonic() - self._t0[0]
            log.info("stats: wall=%.2fs sim=%.2fs rtf=%.3f", wall, self.sim_time - self._t0[1],
                     (self.sim_time - self._t0[1]) / wall if wall > 0 else 0.0)
        self._stop.set()
        if self.cameras is not None:
            self.cameras.signal_stop()
        if self._thread is not None:
            self._thread.join(1.0)
        # Unregistering from the master takes several round trips: overlap it with the cameras.
        def stop_ros() -> None:
            for d in self.drivers:
                d.stop()
            self.ros.stop()
        stoppers = [threading.Thread(target=stop_ros, daemon=True)] if self.ros is not None else []
        for s in stoppers:
            s.start()
        if self.cameras is not None:
            self.cameras.stop()
        deadline = time.monotonic() + 1.0
        for s in stoppers:
            s.join(max(0.0, deadline - time.monotonic()))
        self.world.close()
