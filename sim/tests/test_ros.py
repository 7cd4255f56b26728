"""ROS side: the cell file's device topics (camera streams at the configured rate, sensors), the latched
device faults and the fault service; nothing on topics the cell file does not name.

The sims here run a test cell with other topic names than the demo cell (cells/renamed-topics.yaml), so a
topic hard-coded in the sim would show up as missing data or as an unexpected publication.
"""
from __future__ import annotations

import io
import threading
import time

from pathlib import Path

import dashboard_client
import pytest
import rosgraph
import rospy
import rtde_receive
from cell_msgs.msg import AlarmList, Scatter
from cell_msgs.srv import TriggerFault
from std_srvs.srv import Trigger
from geometry_msgs.msg import PoseArray, WrenchStamped
from PIL import Image
from sensor_msgs.msg import CompressedImage
from visualization_msgs.msg import Marker, MarkerArray

from conftest import wait_for

HOST = "127.0.0.14"
CELLS = Path(__file__).resolve().parent / "cells"
RENAMED = CELLS / "renamed-topics.yaml"
# Stream topic -> the viewpoint the sim must show there (explicit `view`, then cycling by position).
STREAMS = {"/robot2/overview/compressed": "global", "/robot2/overview2/compressed": "global",
           "/robot2/bench/compressed": "workbench"}
WRENCH_TOPICS = ("/robot2/ft_sensor/wrench", "/robot2/ft_sensor/wrench_copy")
TACTILE_TOPIC = "/robot2/finger/tactile"
MARKERS_TOPIC = "/robot2/scene/parts"   # the cell file's scene.markers
# What the sim published before the cell file named its topics; the demo cell still uses these names.
OLD_TOPICS = ("/cell/wrench", "/cell/tactile", "/cell/alarms", "/cell/camera/workbench/image/compressed",
              "/cell/camera/global/image/compressed")


class Recorder:
    def __init__(self, topic: str, mtype) -> None:
        self.msgs: list = []
        self.times: list[float] = []
        self._lock = threading.Lock()
        self.sub = rospy.Subscriber(topic, mtype, self._cb, queue_size=50, buff_size=2 ** 22)

    def _cb(self, msg) -> None:
        with self._lock:
            self.msgs.append(msg)
            self.times.append(time.monotonic())

    def rate(self, skip: int = 3) -> float:
        with self._lock:
            t = self.times[skip:]
        return (len(t) - 1) / (t[-1] - t[0]) if len(t) > 2 else 0.0


def start_ros_sim(start_sim, roscore: str, cell: Path, *args: str):
    # Small frames: this checks the streaming contract (rate, JPEG, views); bench/sim_bench.py measures
    # 640x480 rendering cost. --cell, not CELL_CONFIG: the caller's environment must not choose the cell.
    sim = start_sim(HOST, "--cell", str(cell), "--camera-size", "160x120", "--camera-rate", "6",
                    "--sensor-rate", "40", "--speed", "1", *args, env={"ROS_MASTER_URI": roscore})
    if not rospy.core.is_initialized():
        rospy.init_node("sim_test", anonymous=True, disable_signals=True)
    return sim


@pytest.fixture
def ros_cell(roscore, start_sim):
    return start_ros_sim(start_sim, roscore, RENAMED)


def test_cameras_publish_jpeg_at_configured_rate_on_the_cell_files_streams(ros_cell):
    recs = {topic: Recorder(topic, CompressedImage) for topic in STREAMS}
    wait_for(lambda: all(len(r.msgs) >= 15 for r in recs.values()), 20, what="15 frames per stream")
    for topic, rec in recs.items():
        # The renderer runs at nice 10 so physics wins under CPU load: it may lag (seen at 4.2 Hz on a busy
        # 2-core CI run) but never runs faster than configured.
        assert 3.6 <= rec.rate() <= 7.2, f"{topic}: {rec.rate():.1f} Hz, configured 6 Hz"
        msg = rec.msgs[-1]
        assert msg.format == "jpeg"
        assert msg.header.frame_id == f"camera_{STREAMS[topic]}"
        assert bytes(msg.data[:2]) == b"\xff\xd8"
        img = Image.open(io.BytesIO(bytes(msg.data)))
        img.load()
        assert img.format == "JPEG" and img.size == (160, 120)
        assert len(set(img.convert("L").getdata())) > 20, f"{topic}: blank image"
    wb = bytes(recs["/robot2/bench/compressed"].msgs[-1].data)
    gl = bytes(recs["/robot2/overview/compressed"].msgs[-1].data)
    assert wb != gl, "the two viewpoints must show different views"
    # Each camera reports its frame rate on /diagnostics, as a camera driver does.
    from diagnostic_msgs.msg import DiagnosticArray
    diag = Recorder("/diagnostics", DiagnosticArray)
    wait_for(lambda: diag.msgs and "streaming" in _camera_status(diag.msgs[-1], "Bench").message, 5,
             what="the Bench camera's diagnostics")
    bench = _camera_status(diag.msgs[-1], "Bench")
    values = {kv.key: kv.value for kv in bench.values}
    assert bench.level == 0 and values["topic"] == "/robot2/bench/compressed"
    assert 3.0 <= float(values["frame rate (fps)"]) <= 7.5, values
    for rec in recs.values():
        rec.sub.unregister()
    # Nobody watches any more: idle, not a fault.
    wait_for(lambda: _camera_status(diag.msgs[-1], "Bench").message == "idle: no subscriber", 5,
             what="the camera idle once unwatched")
    diag.sub.unregister()


def _camera_status(array, name: str):
    return next(s for s in array.status if s.name == f"sim_cell: camera {name}")


def _sim_publications() -> dict[str, str]:
    """Topic -> type of everything the sim's node publishes, as the master knows it."""
    master = rosgraph.Master("/sim_test")
    pubs, _, _ = master.getSystemState()
    types = dict(master.getTopicTypes())
    return {topic: types.get(topic, "?") for topic, nodes in pubs if "/sim_cell" in nodes}


@pytest.mark.parametrize("cell, expected", [
    (RENAMED, {**{t: "geometry_msgs/WrenchStamped" for t in WRENCH_TOPICS},
               TACTILE_TOPIC: "cell_msgs/Scatter", MARKERS_TOPIC: "visualization_msgs/MarkerArray",
               **{t: "sensor_msgs/CompressedImage" for t in STREAMS}, "/diagnostics": "diagnostic_msgs/DiagnosticArray"}),
    (CELLS / "no-devices.yaml", {}),
], ids=["renamed-topics", "no-devices"])
def test_sim_publishes_exactly_the_cell_files_topics(roscore, start_sim, cell: Path, expected: dict[str, str]):
    sim = start_ros_sim(start_sim, roscore, cell)
    # No /joint_states: a UR controller speaks RTDE, not ROS; the robot driver publishes them (cell_nodes manual).
    expected = {**expected, "/sim/faults": "cell_msgs/AlarmList", "/sim/objects": "geometry_msgs/PoseArray",
                "/rosout": "rosgraph_msgs/Log"}
    # A previous test's sim unregisters as it stops; give the master a moment rather than race it.
    wait_for(lambda: _sim_publications() == expected, 10,
             what=f"the sim's publications to be exactly {sorted(expected)}")
    assert not set(OLD_TOPICS) & set(_sim_publications())
    if not any(t.endswith("/compressed") for t in expected):
        assert "renderer" not in sim.output()  # no stream in the cell file: no render process either
        assert "0 camera stream(s)" in sim.output()


def test_sensor_topics_faults_and_fault_service(ros_cell):
    wrenches = [Recorder(t, WrenchStamped) for t in WRENCH_TOPICS]
    tactile = Recorder(TACTILE_TOPIC, Scatter)
    faults = Recorder("/sim/faults", AlarmList)
    wait_for(lambda: all(len(r.msgs) > 40 for r in (tactile, *wrenches)), 10, what="sensor messages")
    for rec in (tactile, *wrenches):
        assert 34 <= rec.rate() <= 46, f"{rec.sub.name}: {rec.rate():.1f} Hz, configured 40 Hz"
    for rec in wrenches:
        assert rec.msgs[-1].wrench.force.z < -5  # the gripper hangs from the sensor
        assert rec.msgs[-1].header.frame_id == "ft_sensor"
    assert len(tactile.msgs[-1].x) == 8 and tactile.msgs[-1].header.frame_id == "finger_left_pad"

    # The devices' fault state (latched): what a cell alarms node reads; the sim publishes no alarm list.
    wait_for(lambda: faults.msgs, 5, what="latched fault list on /sim/faults")
    assert {a.id for a in faults.msgs[-1].alarms} == {"protective_stop", "gripper_fault", "door_open", "force_limit"}
    assert not any(a.active for a in faults.msgs[-1].alarms)

    rospy.wait_for_service("/sim/trigger_fault", 5)
    trigger = rospy.ServiceProxy("/sim/trigger_fault", TriggerFault)
    r = rtde_receive.RTDEReceiveInterface(HOST)
    db = dashboard_client.DashboardClient(HOST)
    db.connect()
    try:
        assert trigger("protective_stop").success
        wait_for(lambda: _active(faults) == {"protective_stop"}, 3, what="protective_stop fault")
        wait_for(lambda: r.getSafetyMode() == 3, 2, what="RTDE safety mode PROTECTIVE_STOP")
        assert r.isProtectiveStopped()
        assert db.safetystatus() == "Safetystatus: PROTECTIVE_STOP"

        assert trigger("door_open").success
        assert trigger("gripper_fault").success
        wait_for(lambda: _active(faults) == {"protective_stop", "door_open", "gripper_fault"}, 3, what="faults")

        reply = trigger("earthquake")
        assert not reply.success and "unknown fault" in reply.message

        assert trigger("reset").success
        wait_for(lambda: _active(faults) == set(), 3, what="all faults cleared")
        wait_for(lambda: r.getSafetyMode() == 1, 2, what="safety mode NORMAL")
        assert db.safetystatus() == "Safetystatus: NORMAL"

        assert trigger("door_open").success
        wait_for(lambda: r.getSafetyMode() == 5, 2, what="SAFEGUARD_STOP while the door is open")
        assert db.safetystatus() == "Safetystatus: SAFEGUARD_STOP"
        assert trigger("force_limit").success
        wait_for(lambda: {"force_limit", "protective_stop"} <= _active(faults), 3, what="force limit fault")
        assert trigger("reset").success
        wait_for(lambda: r.getSafetyMode() == 1 and not _active(faults), 3, what="reset")
        inactive = [a for a in faults.msgs[-1].alarms if a.id == "force_limit"][0]
        assert not inactive.active and inactive.since.to_sec() > 0
    finally:
        db.disconnect()
        r.disconnect()


def test_object_poses_on_sim_objects(ros_cell):
    """/sim/objects: the cubes' ground-truth poses (frame base, creation order) at ~5 Hz, where the seed put them."""
    from sim.world import World
    objects = Recorder("/sim/objects", PoseArray)
    wait_for(lambda: len(objects.msgs) >= 8, 5, what="8 object pose messages")
    assert 3.5 <= objects.rate(skip=1) <= 6.5, f"/sim/objects at {objects.rate(skip=1):.1f} Hz, expected ~5 Hz"
    msg = objects.msgs[-1]
    assert msg.header.frame_id == "base" and msg.header.stamp.to_sec() > 0
    replica = World(seed=0)  # the sim's default seed: same placement
    try:
        expected = replica.body_poses()
    finally:
        replica.close()
    assert len(msg.poses) == len(expected) == 3
    for pose, (pos, orn) in zip(msg.poses, expected):
        got = (pose.position.x, pose.position.y, pose.position.z)
        assert max(abs(a - b) for a, b in zip(got, pos)) < 0.002, (got, pos)  # resting parts settle by < 1 mm
        q = (pose.orientation.x, pose.orientation.y, pose.orientation.z, pose.orientation.w)
        assert abs(abs(sum(a * b for a, b in zip(q, orn))) - 1) < 1e-3  # same orientation (q or -q)
    objects.sub.unregister()
    # The feeder: nothing moved yet, so every part is "put back" where it lies (sim/tests/test_restock.py moves them).
    rospy.wait_for_service("/sim/restock", 5)
    answer = rospy.ServiceProxy("/sim/restock", Trigger)()
    assert answer.success and answer.message == "3 parts put back", answer


def test_scene_markers_and_the_arms_robot_description(ros_cell):
    """The cell file's scene section: the parts and stations as a MarkerArray (frame world, ~5 Hz, the cubes where
    the seed put them) and the arm's URDF on its parameter, the revolute joints named as manual.groups names them."""
    import xml.etree.ElementTree as ET
    from sim.scene import PART_COLORS
    from sim.world import World
    markers = Recorder(MARKERS_TOPIC, MarkerArray)
    wait_for(lambda: len(markers.msgs) >= 8, 10, what="8 marker arrays")
    # Never faster than the 5 Hz it is paced at (slower under a loaded host is no fault of the sim).
    assert markers.rate(skip=1) <= 6.5, f"{MARKERS_TOPIC} at {markers.rate(skip=1):.1f} Hz, expected ~5 Hz"
    msg = markers.msgs[-1]
    parts = [m for m in msg.markers if m.ns == "parts"]
    stations = [m for m in msg.markers if m.ns == "stations"]
    assert len(parts) + len(stations) == len(msg.markers)
    assert [m.id for m in parts] == [0, 1, 2] and [m.id for m in stations] == list(range(7))  # the demo fixture
    assert {m.text for m in stations} == {"fixture"}
    for m in msg.markers:
        assert m.header.frame_id == "world" and m.header.stamp.to_sec() > 0
        assert m.type == Marker.CUBE and m.action == Marker.ADD
    replica = World(seed=0)  # the sim's default seed: same placement
    try:
        expected = replica.body_poses()
    finally:
        replica.close()
    for m, (pos, orn), color in zip(parts, expected, PART_COLORS):
        got = (m.pose.position.x, m.pose.position.y, m.pose.position.z)
        assert max(abs(a - b) for a, b in zip(got, pos)) < 0.002, (got, pos)
        q = (m.pose.orientation.x, m.pose.orientation.y, m.pose.orientation.z, m.pose.orientation.w)
        assert abs(abs(sum(a * b for a, b in zip(q, orn))) - 1) < 1e-3
        assert (m.scale.x, m.scale.y, m.scale.z) == (0.04, 0.04, 0.04)
        assert (m.color.r, m.color.g, m.color.b, m.color.a) == pytest.approx(color)
    plate = stations[0]
    assert (plate.pose.position.x, plate.pose.position.y) == pytest.approx((-0.35, 0.35))
    markers.sub.unregister()

    text = rospy.get_param("/robot2/robot_description")
    root = ET.fromstring(text.split("?>", 1)[1])
    revolute = [j.get("name") for j in root.findall("joint") if j.get("type") == "revolute"]
    assert revolute == ["r2_shoulder_pan_joint", "r2_shoulder_lift_joint", "r2_elbow_joint", "r2_wrist_1_joint",
                        "r2_wrist_2_joint", "r2_wrist_3_joint"]
    # Only the parameter the cell file names: an arm's URDF at another name would be another sim's (the roscore is
    # shared with other tests), never this one's renamed joints.
    other = rospy.get_param("/robot_description", "")
    assert "r2_shoulder_pan_joint" not in other


def _active(rec: Recorder) -> set[str]:
    return {a.id for a in rec.msgs[-1].alarms if a.active} if rec.msgs else set()


def test_protective_stop_from_ros_halts_a_moving_arm(ros_cell):
    import numpy as np
    import rtde_control
    rospy.wait_for_service("/sim/trigger_fault", 5)
    trigger = rospy.ServiceProxy("/sim/trigger_fault", TriggerFault)
    r = rtde_receive.RTDEReceiveInterface(HOST)
    c = rtde_control.RTDEControlInterface(HOST)
    try:
        q0 = np.array(r.getActualQ())
        target = q0 + [1.5, 0, 0, 0, 0, 0]
        result: dict[str, bool] = {}
        mover = threading.Thread(target=lambda: result.__setitem__("ok", c.moveJ(list(target), 0.5, 1.0)))
        mover.start()
        wait_for(lambda: r.getActualQ()[0] - q0[0] > 0.2, 5, what="arm moving")
        assert trigger("protective_stop").success
        mover.join(10)
        assert result == {"ok": False}, "a move interrupted by a protective stop must report failure"
        wait_for(lambda: max(abs(v) for v in r.getActualQd()) < 1e-3, 3, what="arm halted")
        q_stop = np.array(r.getActualQ())
        assert 0.2 < q_stop[0] - q0[0] < 1.0
        assert r.getRuntimeState() == 1 and not c.isProgramRunning()
        time.sleep(0.3)
        assert abs(r.getActualQ()[0] - q_stop[0]) < 1e-3, "arm must stay put while protective-stopped"
        assert trigger("reset").success
        wait_for(lambda: r.getSafetyMode() == 1, 3, what="NORMAL after reset")
        assert c.reuploadScript()
        wait_for(c.isProgramRunning, 5, what="control script back")
        assert c.moveJ(list(q0), 1.0, 2.0)
    finally:
        c.stopScript()
        c.disconnect()
        r.disconnect()
