"""ROS 1 side of the simulated cell's devices: sensor topics, camera images, device faults, the fault service.

The device topics are the ones the cell file declares (sim/cell_file.py): the wrist F/T reading of the arm a
WrenchStamped sensor names (default the first) on its topic and the tactile pad on every Scatter sensor topic (sensor
rate), one sensor_msgs/CompressedImage (or, `type: raw`, sensor_msgs/Image) camera per video stream (camera rate, only while the topic has a subscriber).
Fixed names: /sim/faults (latched cell_msgs/AlarmList: the devices' fault state, for the cell's alarms feature to
turn into alarms; the sim publishes no alarm list itself), /sim/objects (geometry_msgs/PoseArray, every part in
creation order at OBJECTS_RATE, frame `base` when the only arm stands at the world origin, else `world`: ground truth
for tests and the UI to see parts move; a real cell has no such topic), the service /sim/trigger_fault
(cell_msgs/TriggerFault) and /sim/restock (std_srvs/Trigger: every part no robot holds or touches back where it lay
at the start, as a feeder or an operator refilling the cell would; for long runs of the process).
The 3D view (the cell file's `scene:` section, sim/cell_file.py parse_scene): on `scene.markers` a
visualization_msgs/MarkerArray of the parts and stations (sim/markers.py, frame `world`) with every /sim/objects
message; at start, for each simulated UR arm whose `scene.arms[]` entry names a `robot_description`, that parameter
set to the arm's URDF (sim/urdf.py) under its motion group's joint names, as the UR bringup would on a real cell
(the ros_control sim's driver sets its arm's own parameter: sim/ros_control/driver.py); with `scene.fixed_frame`,
latched on /tf_static the transform from that frame to each simulated arm's `scene.arms[].base_frame` (sim/frames.py).
No /joint_states: the arm is a UR controller, which speaks RTDE, not ROS; the cell's robot driver
(cell_nodes manual_node) reads it over RTDE and is the only source of /joint_states, as with a real robot.
"""
from __future__ import annotations

import logging
import threading
import time
from collections import deque
from types import SimpleNamespace
from typing import Deque, Optional

from .cell_file import CellDevices, Stream
from .frames import TF_STATIC, base_frames, tf_message
from .markers import marker_array, part_boxes
from .pacing import Pacer
from .safety import Fault
from .stations import station_boxes
from .urdf import urdf_text

log = logging.getLogger("sim.ros")

CAMERA_WINDOW_S = 2.0   # the frame rate a camera's diagnostics report is over the last 2 s


def camera_diagnostic(node: str, stream: Stream, frame_times: "list[float]", watched: bool,
                      now: float) -> tuple[int, str, str, list[tuple[str, str]]]:
    """(level, name, message, values) of a camera's status on /diagnostics, as a camera driver reports it: its
    frame rate; WARN when someone watches and no frame came within the window (a camera renders only while
    watched, so an idle one is fine)."""
    recent = [t for t in frame_times if t >= now - CAMERA_WINDOW_S]
    fps = len(recent) / CAMERA_WINDOW_S
    if not watched:
        level, message = 0, "idle: no subscriber"
    elif not recent:
        level, message = 1, f"no frame for {CAMERA_WINDOW_S:g} s while watched"
    else:
        level, message = 0, f"streaming at {fps:.1f} fps"
    return level, f"{node}: camera {stream.name}", message, [
        ("topic", stream.topic), ("frame rate (fps)", f"{fps:.1f}"), ("view", stream.view)]


OBJECTS_RATE = 5.0  # Hz, /sim/objects and the scene markers (wall time): enough to watch a part being carried,
#                    cheap on the physics lock


def robot_descriptions(devices: CellDevices) -> dict[str, str]:
    """Parameter name -> URDF text of each simulated UR arm the cell file's scene section gives a robot_description."""
    return {d.param: urdf_text(d.tool, d.joint_names) for d in devices.scene.descriptions}


def ros_master_online() -> bool:
    """Check first: rospy.init_node blocks forever without a master."""
    import rosgraph
    try:
        return bool(rosgraph.is_master_online())
    except Exception:
        return False


class RosBridge:
    def __init__(self, cell, devices: CellDevices, sensor_rate: float, speed: float = 1.0,
                 node_name: str = "sim_cell", camera_size: tuple[int, int] = (640, 480)) -> None:
        """`cell`: the sim.cell.Cell (its controllers by group, fault book, lock, world and trigger_fault)."""
        import rospy
        from cell_msgs.msg import AlarmList, Scatter
        from cell_msgs.srv import TriggerFault
        from geometry_msgs.msg import Pose, PoseArray, WrenchStamped
        from sensor_msgs.msg import CompressedImage, Image

        self.rospy = rospy
        self.cell = cell
        self.lock = cell.lock
        several = len(cell.controllers) > 1
        # Frames name the arm when there are several (each has its own sensor).
        self._frame = (lambda group, frame: f"{group}_{frame}") if several else (lambda group, frame: frame)
        # A cell whose arm has its own F/T frame in its robot_description names it (sim/ros_control).
        self._ft_frame = getattr(cell, "ft_frame", None) or (lambda group: self._frame(group, "ft_sensor"))
        self.period = 1.0 / sensor_rate
        # disable_signals: the CLI owns SIGINT/SIGTERM and shuts us down itself.
        root_handlers, root_level = list(logging.root.handlers), logging.root.level
        rospy.init_node(node_name, anonymous=False, disable_signals=True)
        # rospy's logging setup disables every existing logger: give ours (and the console) back.
        for name, lg in logging.root.manager.loggerDict.items():
            if name.startswith("sim") and isinstance(lg, logging.Logger):
                lg.disabled = False
        for h in root_handlers:
            if h not in logging.root.handlers:
                logging.root.addHandler(h)
        logging.root.setLevel(root_level)
        # (group, publisher): each topic carries the wrist F/T of the arm its sensor entry names.
        self.pub_wrench = [(g, rospy.Publisher(t, WrenchStamped, queue_size=10))
                           for t, g in zip(devices.wrench_topics, devices.wrench_groups)]
        self.pub_tactile = [rospy.Publisher(t, Scatter, queue_size=10) for t in devices.tactile_topics]
        self.tactile_group = devices.tactile_group
        # Latched: a node that starts later still learns which faults are active right now.
        self.pub_faults = rospy.Publisher("/sim/faults", AlarmList, queue_size=5, latch=True)
        self.pub_images: list[tuple[Stream, rospy.Publisher]] = [
            (s, rospy.Publisher(s.topic, CompressedImage, queue_size=2)) for s in devices.streams if not s.raw]
        # Raw cameras (sensor_msgs/Image rgb8, `type: raw`), as usb_cam or a GigE driver publishes them.
        self.pub_raw: list[tuple[Stream, rospy.Publisher]] = [
            (s, rospy.Publisher(s.topic, Image, queue_size=1)) for s in devices.streams if s.raw]
        self.camera_size = camera_size
        # The cameras' diagnostics (frame rate per stream), as a real camera driver publishes them.
        self.pub_diagnostics = None
        self._frames: dict[str, Deque[float]] = {s.name: deque(maxlen=200) for s in devices.streams}
        if devices.streams:
            from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
            self._diag_types = SimpleNamespace(DiagnosticArray=DiagnosticArray, DiagnosticStatus=DiagnosticStatus,
                                               KeyValue=KeyValue)
            self.pub_diagnostics = rospy.Publisher("/diagnostics", DiagnosticArray, queue_size=2)
        self._node_name = node_name
        for s in devices.streams:
            log.info("camera %r on %s shows the %s view", s.name, s.topic, s.view)
        # One arm at the origin: the world frame is its base frame (`base`, as before); several arms: `world`.
        arms = cell.world.arms
        self.objects_frame = "base" if len(arms) == 1 and arms[0].at_origin else "world"
        self.pub_objects = rospy.Publisher("/sim/objects", PoseArray, queue_size=2)
        for warning in devices.scene.warnings:
            log.warning("cell file %s: %s", devices.path, warning)
        # What ur_description's bringup loads on a real cell: the arm's URDF, its joints named as the driver's.
        for param, text in robot_descriptions(devices).items():
            rospy.set_param(param, text)
            log.info("URDF of the simulated arm on parameter %s", param)
        self.pub_markers = None
        if devices.scene.markers:
            try:
                from visualization_msgs.msg import MarkerArray
            except ImportError as e:  # the rest of the ROS side still works
                log.error("scene.markers %s: visualization_msgs not importable (%s): run scripts/bootstrap.sh apt",
                          devices.scene.markers, e)
            else:
                self.pub_markers = rospy.Publisher(devices.scene.markers, MarkerArray, queue_size=2)
                self._station_boxes = station_boxes(cell.world.spec)
                self._part_size = cell.world.parts_spec.size
        # Where each arm's base stands, for a view that places the arms from TF (scene.fixed_frame, base_frame).
        self.pub_tf_static = None
        frames = base_frames(devices.scene, cell.world.spec)
        if frames:
            try:
                from geometry_msgs.msg import TransformStamped
                from tf2_msgs.msg import TFMessage
            except ImportError as e:
                log.error("scene.fixed_frame %s: tf2_msgs not importable (%s): run scripts/bootstrap.sh apt",
                          devices.scene.fixed_frame, e)
            else:
                self.pub_tf_static = rospy.Publisher(TF_STATIC, TFMessage, queue_size=1, latch=True)
                self.pub_tf_static.publish(tf_message(frames, rospy.Time.now(), SimpleNamespace(
                    TFMessage=TFMessage, TransformStamped=TransformStamped)))
                for f in frames:
                    log.info("TF %s -> %s at %s on %s", f.parent, f.child, list(f.translation), TF_STATIC)
        self._types = dict(AlarmList=AlarmList, Scatter=Scatter, WrenchStamped=WrenchStamped,
                           CompressedImage=CompressedImage, Image=Image, Pose=Pose, PoseArray=PoseArray)
        self.service = rospy.Service("/sim/trigger_fault", TriggerFault, self._trigger_fault)
        from std_srvs.srv import Trigger
        self.restock_service = rospy.Service("/sim/restock", Trigger, self._restock)
        self._stop = threading.Event()
        self._thread: Optional[threading.Thread] = None
        self._objects_thread: Optional[threading.Thread] = None
        self.published = 0

    def start(self) -> None:
        self.cell.faults.subscribe(self._publish_faults)
        self._thread = threading.Thread(target=self._sensor_loop, name="ros-sensors", daemon=True)
        self._thread.start()
        self._objects_thread = threading.Thread(target=self._objects_loop, name="ros-objects", daemon=True)
        self._objects_thread.start()

    def stop(self) -> None:
        self._stop.set()
        for t in (self._thread, self._objects_thread):
            if t is not None:
                t.join(1.0)
        self.service.shutdown("sim stopping")
        self.restock_service.shutdown("sim stopping")
        self.rospy.signal_shutdown("sim stopping")

    # ---- publishers ---------------------------------------------------------------------------
    def _sensor_loop(self) -> None:
        pacer = Pacer(self.period, self._stop)
        while not self._stop.is_set():
            try:
                self._publish_sensors()
            except Exception:
                log.exception("sensor publish failed")
            pacer.wait()

    def _publish_sensors(self) -> None:
        stamp = self.rospy.Time.now()
        wrenches = {}
        for group, pub in self.pub_wrench:
            if group not in wrenches:
                w = self._types["WrenchStamped"]()
                w.header.stamp = stamp
                w.header.frame_id = self._ft_frame(group)
                f = self.cell.controllers[group].snapshot.ft_raw
                w.wrench.force.x, w.wrench.force.y, w.wrench.force.z = float(f[0]), float(f[1]), float(f[2])
                w.wrench.torque.x, w.wrench.torque.y, w.wrench.torque.z = float(f[3]), float(f[4]), float(f[5])
                wrenches[group] = w
            pub.publish(wrenches[group])
        if self.pub_tactile:  # the contact query holds the physics lock: skip it when no cell topic wants it
            with self.lock:  # contact queries touch the physics client
                xs, forces = self.cell.controllers[self.tactile_group].body.tactile()
            t = self._types["Scatter"]()
            t.header.stamp = stamp
            t.header.frame_id = self._frame(self.tactile_group, "finger_left_pad")
            t.x, t.y = xs, forces
            for pub in self.pub_tactile:
                pub.publish(t)
        self.published += 1

    def _objects_loop(self) -> None:
        pacer = Pacer(1.0 / OBJECTS_RATE, self._stop)
        last_diagnostics = 0.0
        while not self._stop.is_set():
            try:
                self._publish_objects()
                if self.pub_diagnostics is not None and time.monotonic() - last_diagnostics >= 1.0:
                    last_diagnostics = time.monotonic()
                    self._publish_diagnostics()
            except Exception:
                log.exception("objects publish failed")
            pacer.wait()

    def _publish_diagnostics(self) -> None:
        d = self._diag_types
        now = time.monotonic()
        out = d.DiagnosticArray()
        out.header.stamp = self.rospy.Time.now()
        for s, pub in self.pub_images + self.pub_raw:
            level, name, message, values = camera_diagnostic(self._node_name, s, list(self._frames[s.name]),
                                                             pub.get_num_connections() > 0, now)
            out.status.append(d.DiagnosticStatus(level=level, name=name, message=message, hardware_id=s.topic,
                                                 values=[d.KeyValue(key=k, value=v) for k, v in values]))
        assert self.pub_diagnostics is not None
        self.pub_diagnostics.publish(out)

    def _publish_objects(self) -> None:
        with self.lock:  # the physics client is the controller loop's: read between two ticks
            poses = self.cell.world.body_poses()
        stamp = self.rospy.Time.now()
        out = self._types["PoseArray"]()
        out.header.stamp = stamp
        out.header.frame_id = self.objects_frame
        for (x, y, z), (qx, qy, qz, qw) in poses:
            m = self._types["Pose"]()
            m.position.x, m.position.y, m.position.z = float(x), float(y), float(z)
            o = m.orientation
            o.x, o.y, o.z, o.w = float(qx), float(qy), float(qz), float(qw)
            out.poses.append(m)
        self.pub_objects.publish(out)
        if self.pub_markers is not None and self.pub_markers.get_num_connections() > 0:
            self.pub_markers.publish(marker_array(part_boxes(poses, self._part_size), self._station_boxes, stamp))

    def watched_views(self) -> set[str]:
        """Viewpoints shown by at least one stream whose image topic has a subscriber right now."""
        return {s.view for s, pub in self.pub_images if pub.get_num_connections() > 0}

    def raw_size(self, s: Stream) -> tuple[int, int]:
        return s.size or self.camera_size

    def wanted(self) -> dict[str, set[tuple[int, int]]]:
        """The raw images someone subscribes to: viewpoint -> sizes (sim.cameras.RawOutputs)."""
        out: dict[str, set[tuple[int, int]]] = {}
        for s, pub in self.pub_raw:
            if pub.get_num_connections() > 0:
                out.setdefault(s.view, set()).add(self.raw_size(s))
        return out

    def publish(self, view: str, size: tuple[int, int], pixels: bytes) -> None:
        """One viewpoint's raw pixels (rgb8) at `size` to every raw stream showing it at that size."""
        msg = self._types["Image"]()
        msg.header.stamp = self.rospy.Time.now()
        msg.header.frame_id = f"camera_{view}"
        msg.width, msg.height = size
        msg.encoding, msg.is_bigendian, msg.step = "rgb8", 0, size[0] * 3
        msg.data = pixels
        now = time.monotonic()
        for s, pub in self.pub_raw:
            if s.view == view and self.raw_size(s) == size and pub.get_num_connections() > 0:
                pub.publish(msg)
                self._frames[s.name].append(now)

    def publish_image(self, view: str, jpeg: bytes) -> None:
        """One rendered viewpoint goes to every stream showing it (rospy skips topics without subscribers)."""
        msg = self._types["CompressedImage"]()
        msg.header.stamp = self.rospy.Time.now()
        msg.header.frame_id = f"camera_{view}"
        msg.format = "jpeg"
        msg.data = jpeg
        now = time.monotonic()
        for s, pub in self.pub_images:
            if s.view == view and pub.get_num_connections() > 0:
                pub.publish(msg)
                self._frames[s.name].append(now)

    def _publish_faults(self, faults: list[Fault]) -> None:
        from cell_msgs.msg import Alarm as AlarmMsg
        out = self._types["AlarmList"]()
        out.header.stamp = self.rospy.Time.now()
        for f in faults:
            m = AlarmMsg()
            m.id, m.text, m.severity, m.active = f.id, f.text, f.severity, f.active
            m.since = self.rospy.Time.from_sec(f.since)
            out.alarms.append(m)
        self.pub_faults.publish(out)

    def _restock(self, _req):
        from std_srvs.srv import TriggerResponse
        ok, message = self.cell.restock()
        log.info("restock: %s", message)
        return TriggerResponse(success=ok, message=message)

    def _trigger_fault(self, req):
        from cell_msgs.srv import TriggerFaultResponse
        ok, message = self.cell.trigger_fault(req.fault.strip())
        log.info("trigger_fault(%s): %s", req.fault, message)
        return TriggerFaultResponse(success=ok, message=message)
