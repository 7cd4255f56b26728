"""The 3D view's inputs the sim makes (the cell file's `scene:` section), without ROS: the URDF under the joint names the
robot driver publishes (sim/urdf.py), the section's parsing (sim/cell_file.py parse_scene), the stations' geometry as
built in the physics (sim/stations.py) and the MarkerArray of parts and stations (sim/markers.py)."""
from __future__ import annotations

import copy
import math
import re
import xml.etree.ElementTree as ET
from pathlib import Path
from types import SimpleNamespace

import pybullet
import pytest
import yaml
from pybullet_utils import bullet_client
from geometry_msgs.msg import TransformStamped
from tf2_msgs.msg import TFMessage
from visualization_msgs.msg import Marker

from sim import urdf
from sim.cell_file import ArmDescription, CellFileError, SceneSpec, devices_from, load_devices
from sim.frames import base_frames, tf_message
from sim.markers import marker_array, part_boxes
from sim.ros_bridge import OBJECTS_RATE, robot_descriptions
from sim.scene import PART_COLORS, PartsSpec, StationSpec, WorldSpec
from sim.stations import Box, station_boxes
from sim.world import World

ROOT = Path(__file__).resolve().parents[2]
DEMO = ROOT / "config" / "demo-cell.yaml"
TWIN = ROOT / "config" / "twin-arm-cell.yaml"
IIWA = ROOT / "config" / "iiwa-cell.yaml"
CELLS = Path(__file__).resolve().parent / "cells"
LEFT = [f"left_{j}" for j in urdf.ARM_JOINTS]
RIGHT = [f"right_{j}" for j in urdf.ARM_JOINTS]
TWIN_SCENE = {"markers": "/sim/parts",
              "arms": [{"group": "left", "robot_description": "/left/robot_description", "base": [-0.48, 0, 0, 180]},
                       {"group": "right", "robot_description": "/right/robot_description", "base": [0.48, 0, 0, 0]}]}


def doc_with_scene(path: Path, scene) -> dict:
    """The cell file with this scene section (whatever scene the file has itself)."""
    doc = yaml.safe_load(path.read_text())
    doc["scene"] = copy.deepcopy(scene)
    return doc


def joints_of(text: str) -> list[tuple[str, str]]:
    root = ET.fromstring(text.split("?>", 1)[1])
    return [(j.get("name"), j.get("type")) for j in root.findall("joint")]


# ---------------------------------------------------------------------------------------------- URDF
def test_urdf_default_names_are_the_physics_ones() -> None:
    for tool in urdf.TOOLS:
        assert urdf.urdf_text(tool) == urdf.urdf_text(tool, urdf.ARM_JOINTS)
        revolute = [n for n, t in joints_of(urdf.urdf_text(tool)) if t == "revolute"]
        assert revolute == urdf.ARM_JOINTS


@pytest.mark.parametrize("tool", urdf.TOOLS)
def test_urdf_with_the_groups_joint_names_renames_only_the_arm_joints(tool: str) -> None:
    plain, renamed = urdf.urdf_text(tool), urdf.urdf_text(tool, LEFT)
    assert [n for n, t in joints_of(renamed) if t == "revolute"] == LEFT
    # everything else is the same text: links, origins, limits, the tool's joints
    assert renamed == plain.replace('<joint name="', '<joint name="left_').replace(
        '<joint name="left_flange', '<joint name="flange').replace('<joint name="left_ft', '<joint name="ft').replace(
        '<joint name="left_finger', '<joint name="finger').replace('<joint name="left_gripper', '<joint name="gripper') \
        .replace('<joint name="left_vacuum', '<joint name="vacuum').replace('<joint name="left_cup', '<joint name="cup')
    others = [n for n, t in joints_of(renamed) if t != "revolute"]
    assert others == [n for n, t in joints_of(plain) if t != "revolute"]


def test_renamed_urdf_loads_with_the_same_kinematics(tmp_path: Path) -> None:
    p = bullet_client.BulletClient(connection_mode=pybullet.DIRECT)
    try:
        bodies = []
        for k, names in enumerate((None, RIGHT)):
            path = tmp_path / f"arm{k}.urdf"
            path.write_text(urdf.urdf_text("vacuum", names))
            bodies.append(p.loadURDF(str(path), useFixedBase=True))
        infos = [[p.getJointInfo(b, j) for j in range(p.getNumJoints(b))] for b in bodies]
        assert [i[1].decode() for i in infos[1] if i[2] == pybullet.JOINT_REVOLUTE] == RIGHT
        q = [0.3, -1.2, 1.1, -0.7, 0.4, 0.2]
        for b, info in zip(bodies, infos):
            arm = [i[0] for i in info if i[2] == pybullet.JOINT_REVOLUTE]
            for j, v in zip(arm, q):
                p.resetJointState(b, j, v)
        tips = [p.getLinkState(b, p.getNumJoints(b) - 1, computeForwardKinematics=1)[4] for b in bodies]
        assert max(abs(a - c) for a, c in zip(*tips)) < 1e-9
    finally:
        p.disconnect()


@pytest.mark.parametrize("names", [LEFT[:5], LEFT[:5] + LEFT[:1], ["a"] * 6, [*LEFT[:5], "finger_left_joint"]])
def test_urdf_refuses_joint_names_that_do_not_fit(names) -> None:
    with pytest.raises(ValueError):
        urdf.urdf_text("gripper", names)


def test_joint_names_are_written_as_xml_attributes() -> None:
    odd = ['a"<&_shoulder_pan_joint', *urdf.ARM_JOINTS[1:]]
    assert [n for n, t in joints_of(urdf.urdf_text("gripper", odd)) if t == "revolute"] == odd


@pytest.mark.parametrize("group, expected", [
    ([], urdf.ARM_JOINTS),
    (urdf.ARM_JOINTS, urdf.ARM_JOINTS),
    (LEFT, LEFT),
    (list(reversed(RIGHT)), RIGHT),  # by name, not by position
    (["r2_wrist_3_joint", "r2_shoulder_pan_joint"], [f"r2_{j}" for j in urdf.ARM_JOINTS]),  # the rest: the prefix
    (["tool_wrist_3_joint"], [f"tool_{j}" for j in urdf.ARM_JOINTS]),
])
def test_ur_joint_names_follow_the_drivers_rule(group, expected) -> None:
    assert urdf.ur_joint_names(group) == list(expected)


@pytest.mark.parametrize("group, message", [
    (["left_knee_joint"], "is not a joint of the UR arm"),
    (["a_elbow_joint", "b_elbow_joint"], "same robot joint (elbow_joint)"),
])
def test_ur_joint_names_refuse_what_the_driver_refuses(group, message) -> None:
    with pytest.raises(ValueError, match=re.escape(message)):
        urdf.ur_joint_names(group)


# ---------------------------------------------------------------------------------------------- scene section
def test_no_scene_section_publishes_nothing_for_the_view() -> None:
    for path in (CELLS / "no-devices.yaml", CELLS / "iiwa-test.yaml"):
        doc = yaml.safe_load(path.read_text())
        doc.pop("scene", None)
        assert devices_from(doc, str(path)).scene == SceneSpec()


def test_twin_cell_scene_gives_each_arm_its_urdf_under_its_groups_joint_names() -> None:
    d = devices_from(doc_with_scene(TWIN, TWIN_SCENE), str(TWIN))
    assert d.scene.markers == "/sim/parts" and d.scene.warnings == ()
    assert d.scene.descriptions == (ArmDescription("/left/robot_description", "left", "gripper", tuple(LEFT)),
                                    ArmDescription("/right/robot_description", "right", "vacuum", tuple(RIGHT)))
    params = robot_descriptions(d)
    assert set(params) == {"/left/robot_description", "/right/robot_description"}
    left, right = joints_of(params["/left/robot_description"]), joints_of(params["/right/robot_description"])
    assert [n for n, t in left if t == "revolute"] == LEFT and [n for n, t in right if t == "revolute"] == RIGHT
    assert ("finger_left_joint", "prismatic") in left and ("cup_mount", "fixed") in right
    # exactly the joint names of manual.groups (what the driver publishes on /joint_states)
    groups = {g["name"]: g["joints"] for g in yaml.safe_load(TWIN.read_text())["manual"]["groups"]}
    assert (groups["left"], groups["right"]) == (LEFT, RIGHT)


def test_demo_cell_scene() -> None:
    scene = {"markers": "/sim/parts", "arms": [{"group": "arm", "robot_description": "/robot_description"}]}
    d = devices_from(doc_with_scene(DEMO, scene), str(DEMO))
    assert d.scene.descriptions == (ArmDescription("/robot_description", "arm", "gripper", tuple(urdf.ARM_JOINTS)),)
    assert robot_descriptions(d) == {"/robot_description": urdf.urdf_text("gripper")}
    assert d.scene.warnings == ()


def test_a_scene_arm_without_robot_description_sets_no_parameter() -> None:
    d = devices_from(doc_with_scene(DEMO, {"arms": [{"group": "arm"}]}), str(DEMO))
    assert d.scene.markers is None and d.scene.descriptions == () and robot_descriptions(d) == {}


def test_ros_control_arms_get_their_urdf_from_their_driver_not_from_the_ur_sim() -> None:
    scene = {"markers": "/sim/parts", "arms": [{"group": "arm"}]}
    d = devices_from(doc_with_scene(IIWA, scene), str(IIWA))
    assert d.scene.markers == "/sim/parts" and d.scene.descriptions == () and d.scene.warnings == ()
    # a parameter other than the driver's is named: the view would read one nobody sets
    scene["arms"][0]["robot_description"] = "/other/robot_description"
    d = devices_from(doc_with_scene(IIWA, scene), str(IIWA))
    assert d.scene.descriptions == ()
    assert len(d.scene.warnings) == 1 and "/iiwa/robot_description" in d.scene.warnings[0]


def test_warnings_where_the_view_would_disagree_with_the_sim() -> None:
    scene = copy.deepcopy(TWIN_SCENE)
    del scene["arms"][1]["base"]                        # the right arm stands at x = 0.48
    scene["arms"][0]["base"] = [-0.48, 0, 0, -180]      # the same turn as 180
    d = devices_from(doc_with_scene(TWIN, scene), str(TWIN))
    assert len(d.scene.warnings) == 1 and d.scene.warnings[0].startswith("scene.arms[1].base: [0.0, 0.0, 0.0, 0.0]")
    assert len(d.scene.descriptions) == 2  # a warning only: the parameters are still set
    # a motion group the sim does not simulate: nothing sets its parameter
    doc = doc_with_scene(TWIN, TWIN_SCENE)
    doc["simulation"]["arms"] = doc["simulation"]["arms"][:1]
    doc["sensors"] = [s for s in doc["sensors"] if s.get("group") != "right"]
    d = devices_from(doc, str(TWIN))
    assert [a.group for a in d.scene.descriptions] == ["left"]
    assert any("group 'right' is no simulated arm" in w for w in d.scene.warnings)


def test_tf_places_each_simulated_arm_where_the_sim_built_it() -> None:
    scene = {"markers": "/sim/parts", "fixed_frame": "world",
             "arms": [{"group": "left", "robot_description": "/left/robot_description", "base_frame": "left_base_link"},
                      {"group": "right", "robot_description": "/right/robot_description"}]}
    d = devices_from(doc_with_scene(TWIN, scene), str(TWIN))
    # the left base comes from TF: no base to disagree with; the right one has the default base, 0.48 m off
    assert [w.split(":")[0] for w in d.scene.warnings] == ["scene.arms[1].base"]
    [left] = base_frames(d.scene, d.world)
    assert (left.parent, left.child) == ("world", "left_base_link")
    assert left.translation == pytest.approx((-0.48, 0.0, 0.0))
    assert left.rotation == pytest.approx((0.0, 0.0, 1.0, 0.0))   # turned 180 degrees about z
    msg = tf_message([left], stamp=7, types=SimpleNamespace(TFMessage=TFMessage, TransformStamped=TransformStamped))
    [t] = msg.transforms
    assert (t.header.frame_id, t.child_frame_id, t.header.stamp) == ("world", "left_base_link", 7)
    assert (t.transform.translation.x, t.transform.rotation.z, t.transform.rotation.w) == pytest.approx((-0.48, 1.0, 0.0))
    # no fixed frame: no TF at all
    assert base_frames(devices_from(doc_with_scene(TWIN, TWIN_SCENE), str(TWIN)).scene, d.world) == []


@pytest.mark.parametrize("scene, where", [
    (["/sim/parts"], "scene: expected a mapping"),
    ({"markers": "sim/parts"}, "scene.markers: expected a global ROS name"),
    ({"markers": "/sim//parts"}, "scene.markers"),
    ({"markers": "/sim/objects"}, "scene.markers: /sim/objects is already used by the sim itself"),
    ({"markers": "/cell/left/wrench"}, "scene.markers: /cell/left/wrench is already used by a wrench sensor"),
    ({"arms": {"group": "left"}}, "scene.arms: expected a list"),
    ({"arms": ["left"]}, "scene.arms[0]: expected a mapping"),
    ({"arms": [{"robot_description": "/r"}]}, "scene.arms[0].group"),
    ({"arms": [{"group": "middle"}]}, "scene.arms[0].group: 'middle' is not a motion group"),
    ({"arms": [{"group": "left"}, {"group": "left"}]}, "scene.arms[1].group: 'left' is already"),
    ({"arms": [{"group": "left", "robot_description": "robot_description"}]}, "scene.arms[0].robot_description"),
    ({"arms": [{"group": "left", "robot_description": "/d"}, {"group": "right", "robot_description": "/d"}]},
     "scene.arms[1].robot_description: /d is already the parameter of group 'left'"),
    ({"arms": [{"group": "left", "base": [0, 0, 0]}]}, "scene.arms[0].base: expected [x, y, z, yaw_deg]"),
    ({"arms": [{"group": "left", "base": [0, 0, 0, "90"]}]}, "scene.arms[0].base"),
    ({"fixed_frame": "/world", "arms": [{"group": "left"}]}, "scene.fixed_frame: expected a TF frame name"),
    ({"arms": [{"group": "left", "base_frame": "left_base"}]}, "scene.arms[0].base_frame: needs scene.fixed_frame"),
    ({"fixed_frame": "world", "arms": [{"group": "left", "base_frame": "a b"}]}, "scene.arms[0].base_frame: expected"),
])
def test_unusable_scene_sections_name_the_field(scene, where: str) -> None:
    with pytest.raises(CellFileError) as e:
        devices_from(doc_with_scene(TWIN, scene), "x.yaml")
    assert str(e.value).startswith("cell file x.yaml: ") and where in str(e.value), str(e.value)


def test_group_joints_that_are_no_ur_joints_set_no_urdf_and_say_so() -> None:
    # The manual section's own check refuses the joint name (one problem, reported once); the sim sets no URDF.
    doc = doc_with_scene(TWIN, TWIN_SCENE)
    doc["manual"]["groups"][1]["joints"][2] = "right_knee_joint"
    scene = devices_from(doc, "x.yaml").scene
    assert [d.group for d in scene.descriptions] == ["left"]
    assert any(w.startswith("manual.groups[1].joints: 'right_knee_joint' is not a joint") for w in scene.warnings), scene.warnings


# ---------------------------------------------------------------------------------------------- stations, markers
def physics_boxes(world: World) -> list[tuple]:
    """(centre, size, orientation) of every visual box of every station body, as the physics has them."""
    p, out = world.p, []
    for body in world.stations.values():
        pos, orn = p.getBasePositionAndOrientation(body)
        for shape in p.getVisualShapeData(body):
            assert shape[2] == pybullet.GEOM_BOX
            c, o = p.multiplyTransforms(pos, orn, shape[5], shape[6])
            out.append((c, shape[3], o, shape[7]))
    return out


def same_rotation(a, b) -> bool:
    return abs(abs(sum(x * y for x, y in zip(a, b))) - 1) < 1e-6


YAWED = WorldSpec(parts=PartsSpec(count=0), stations=(
    StationSpec(name="row", kind="fixture", position=(-0.3, 0.3), yaw=math.radians(30), pockets=4),
    StationSpec(name="free", kind="fixture", yaw=math.radians(-20), pockets=((0.2, 0.2), (0.3, 0.25))),
    StationSpec(name="stand", kind="stand", position=(0.1, -0.3), yaw=math.radians(45), size=(0.1, 0.06), height=0.12),
))


@pytest.mark.parametrize("spec", [
    load_devices(str(DEMO)).world, load_devices(str(TWIN)).world, load_devices(str(CELLS / "iiwa-test.yaml")).world,
    YAWED,
], ids=["demo", "twin", "iiwa-test", "yawed"])
def test_station_boxes_are_what_the_physics_built(spec) -> None:
    world = World(spec=WorldSpec(arms=(), parts=spec.parts, stations=spec.stations))
    try:
        built = physics_boxes(world)
    finally:
        world.close()
    boxes = station_boxes(spec)
    assert len(boxes) == len(built) > 0
    for box, (centre, size, orn, rgba) in zip(boxes, built):
        assert max(abs(a - b) for a, b in zip(box.centre, centre)) < 1e-6, (box, centre)  # float32 there
        assert max(abs(a - b) for a, b in zip(box.size, size)) < 1e-6
        assert same_rotation(box.orientation, orn)
        assert max(abs(a - b) for a, b in zip(box.rgba, rgba)) < 1e-6  # the physics keeps colours as float32
    names = [b.name for b in boxes]
    assert names == sorted(names, key=[s.name for s in spec.stations].index)  # station by station


def test_demo_fixture_boxes() -> None:
    boxes = station_boxes(load_devices(str(DEMO)).world)
    assert len(boxes) == 7 and {b.name for b in boxes} == {"fixture"}  # plate, 2 long walls, 4 cross walls
    plate = boxes[0]
    assert plate.centre == pytest.approx((-0.35, 0.35, 0.003)) and plate.size == pytest.approx((0.2, 0.184, 0.006))
    assert plate.orientation == (0.0, 0.0, 0.0, 1.0) and plate.rgba == (0.6, 0.6, 0.65, 1.0)


def test_twin_stand_box() -> None:
    boxes = station_boxes(load_devices(str(TWIN)).world)
    stand = [b for b in boxes if b.name == "hand_over"]
    assert stand == [Box("hand_over", (0.0, 0.0, 0.04), (0.08, 0.08, 0.08), (0.0, 0.0, 0.0, 1.0),
                         (0.45, 0.5, 0.55, 1.0))]
    assert len([b for b in boxes if b.name == "output"]) == 1 + 4 * 3  # plate, 4 walls per pocket


def test_marker_array_of_parts_and_stations() -> None:
    from genpy import Time
    poses = [((0.1, 0.2, 0.02), (0.0, 0.0, 0.0, 1.0)), ((0.3, -0.1, 0.3), (0.0, 0.0, 0.3826834, 0.9238795))]
    parts = part_boxes(poses, 0.04)
    stations = station_boxes(load_devices(str(TWIN)).world)
    msg = marker_array(parts, stations, Time(12, 5))
    assert len(msg.markers) == 2 + len(stations) == 16
    for m in msg.markers:
        assert m.type == Marker.CUBE and m.action == Marker.ADD and m.header.frame_id == "world"
        assert m.header.stamp == Time(12, 5) and m.lifetime.is_zero() and not m.frame_locked
    for i, (m, (pos, orn)) in enumerate(zip(msg.markers[:2], poses)):
        assert (m.ns, m.id) == ("parts", i)
        assert (m.pose.position.x, m.pose.position.y, m.pose.position.z) == pos
        assert (m.pose.orientation.x, m.pose.orientation.y, m.pose.orientation.z, m.pose.orientation.w) == orn
        assert (m.scale.x, m.scale.y, m.scale.z) == (0.04, 0.04, 0.04)
        assert (m.color.r, m.color.g, m.color.b, m.color.a) == PART_COLORS[i]
    assert [(m.ns, m.id) for m in msg.markers[2:]] == [("stations", k) for k in range(len(stations))]
    stand = msg.markers[2]
    assert stand.text == "hand_over" and (stand.scale.x, stand.scale.y, stand.scale.z) == (0.08, 0.08, 0.08)
    assert (stand.pose.position.x, stand.pose.position.y, stand.pose.position.z) == (0.0, 0.0, 0.04)
    assert (stand.color.r, stand.color.g, stand.color.b, stand.color.a) == (0.45, 0.5, 0.55, 1.0)
    assert {m.text for m in msg.markers[3:]} == {"output"}
    # it serialises (what rospy does on publish)
    import io
    buf = io.BytesIO()
    msg.serialize(buf)
    assert buf.tell() > 0


def test_marker_colours_cycle_and_the_stamp_defaults_to_zero() -> None:
    parts = part_boxes([((0.0, 0.0, 0.02), (0.0, 0.0, 0.0, 1.0))] * 8, 0.05)
    msg = marker_array(parts, [])
    assert [m.id for m in msg.markers] == list(range(8))
    assert [(m.color.r, m.color.g, m.color.b, m.color.a) for m in msg.markers] == [
        PART_COLORS[i % len(PART_COLORS)] for i in range(8)]
    assert all(m.header.stamp.is_zero() and m.scale.z == 0.05 for m in msg.markers)


def test_markers_of_the_physics_world_sit_on_the_cubes() -> None:
    world = World(seed=0)
    try:
        poses = world.body_poses()
        msg = marker_array(part_boxes(poses, world.parts_spec.size), station_boxes(world.spec))
    finally:
        world.close()
    parts = [m for m in msg.markers if m.ns == "parts"]
    assert len(parts) == 3 and all(abs(m.pose.position.z - 0.02) < 1e-6 for m in parts)
    assert [(m.pose.position.x, m.pose.position.y) for m in parts] == [(pos[0], pos[1]) for pos, _ in poses]


def test_markers_go_with_the_objects_at_about_5_hz() -> None:
    assert OBJECTS_RATE == 5.0
