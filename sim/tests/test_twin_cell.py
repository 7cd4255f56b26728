"""The twin-arm cell (config/twin-arm-cell.yaml): one sim process, one physics world, two UR controllers on their own
addresses; each moves only its own arm; the cell file's hand-over process, driven step by step with the unmodified
ur_rtde client, takes the cubes from the left arm's gripper over the stand to the right arm's vacuum tool and into
the fixture's pockets.
"""
from __future__ import annotations

import math
import socket
import threading
import time
from pathlib import Path

import dashboard_client
import numpy as np
import pytest
import rtde_control
import rtde_io
import rtde_receive
import yaml

from conftest import wait_for
from sim import kinematics as kin

ROOT = Path(__file__).resolve().parents[2]
TWIN = ROOT / "config" / "twin-arm-cell.yaml"
LEFT, RIGHT = "127.0.3.1", "127.0.3.2"
HOSTS = {"left": LEFT, "right": RIGHT}
SPEED = 3.0
WRENCH_TYPE = "geometry_msgs/WrenchStamped"


def twin_doc() -> dict:
    return yaml.safe_load(TWIN.read_text())


def start_twin(start_sim, *args: str, env=None):
    # --host is the fallback of groups without a host; --hosts puts both arms on test addresses (the cell file's own
    # 127.0.2.x stay free for a running stack).
    sim = start_sim(LEFT, "--cell", str(TWIN), "--hosts", f"left={LEFT},right={RIGHT}", "--speed", str(SPEED),
                    "--no-cameras", *args, env=env)
    wait_for(lambda: all(_open(RIGHT, port) for port in (30004, 29999, 30003)), 10, what="right arm's ports")
    return sim


def _open(host: str, port: int) -> bool:
    try:
        with socket.create_connection((host, port), timeout=0.2):
            return True
    except OSError:
        return False


class Arm:
    """One arm's ur_rtde clients (`frequency`: of their RTDE streams; -1: the e-Series' 500 Hz)."""

    def __init__(self, host: str, frequency: float = -1.0) -> None:
        self.host = host
        self.r = rtde_receive.RTDEReceiveInterface(host, frequency)
        self.c = rtde_control.RTDEControlInterface(host, frequency)
        self.io = rtde_io.RTDEIOInterface(host)

    def close(self) -> None:
        self.c.stopScript()
        for x in (self.io, self.c, self.r):
            x.disconnect()


@pytest.fixture
def arms(start_sim):
    start_twin(start_sim, "--no-ros")
    made = {g: Arm(h) for g, h in HOSTS.items()}
    yield made
    for a in made.values():
        a.close()


def test_each_controller_answers_on_its_own_host_and_moves_only_its_arm(arms):
    for host in HOSTS.values():
        db = dashboard_client.DashboardClient(host)
        db.connect()
        try:
            assert db.robotmode() == "Robotmode: RUNNING"
            assert db.safetystatus() == "Safetystatus: NORMAL"
        finally:
            db.disconnect()
    start = {g: np.array(a.r.getActualQ()) for g, a in arms.items()}
    doc = twin_doc()
    for g, a in arms.items():  # the arms boot where the cell file says (simulation.arms[].start_joints)
        arm = next(x for x in doc["simulation"]["arms"] if x["group"] == g)
        assert np.max(np.abs(start[g] - arm["start_joints"])) < 1e-3
    # The left arm moves alone: the right one stays put.
    target = start["left"] + [0.3, 0, 0, 0, 0, 0.4]
    assert arms["left"].c.moveJ(list(target), 1.0, 2.0)
    wait_for(lambda: np.max(np.abs(np.array(arms["left"].r.getActualQ()) - target)) < 1e-3, 2, what="left at target")
    assert np.max(np.abs(np.array(arms["right"].r.getActualQ()) - start["right"])) < 1e-4
    # Both at once, each to its own target.
    targets = {"left": start["left"], "right": start["right"] + [0, 0.2, -0.2, 0, 0, -0.5]}
    results: dict[str, bool] = {}
    threads = [threading.Thread(target=lambda g=g: results.__setitem__(g, arms[g].c.moveJ(list(targets[g]), 1.0, 2.0)))
               for g in arms]
    for t in threads:
        t.start()
    for t in threads:
        t.join(30)
    assert results == {"left": True, "right": True}
    for g, a in arms.items():  # (this receiver's stream may trail the control client's under load)
        wait_for(lambda: np.max(np.abs(np.array(a.r.getActualQ()) - targets[g])) < 1e-3, 2,
                 what=f"{g} at its own target")
    # Each controller reports its TCP in its own base frame: the same joints give the same pose on both arms.
    q = [-0.5, -1.2, 1.4, -1.8, -1.5708, 0.3]
    assert arms["left"].c.moveJ(q, 1.0, 2.0) and arms["right"].c.moveJ(q, 1.0, 2.0)
    for g, a in arms.items():
        wait_for(lambda: np.max(np.abs(np.array(a.r.getActualQ()) - q)) < 1e-4, 2, what=f"{g} at q")
    pl, pr = np.array(arms["left"].r.getActualTCPPose()), np.array(arms["right"].r.getActualTCPPose())
    # ... up to the tool: the vacuum cup's TCP is 0.035 m shorter than the fingertips, along the tool z axis.
    tool_z = kin.rotvec_to_matrix(pl[3:])[:, 2]
    np.testing.assert_allclose(pl[:3] - pr[:3], (0.125 - 0.09) * tool_z, atol=1e-3)
    # Each has its own IO: DO4 on the right arm is not the left arm's.
    assert arms["right"].io.setStandardDigitalOut(4, True)
    wait_for(lambda: arms["right"].r.getDigitalOutState(4), 2, what="right DO4")
    assert not arms["left"].r.getDigitalOutState(4)
    assert arms["right"].io.setStandardDigitalOut(4, False)


# ---------------------------------------------------------------------------------------------- the hand-over
class ProcessRunner:
    """Runs the cell file's process operations the way the process executor does through the robot driver (moves:
    move_named -> moveJ, move_pose/move_relative -> moveL; tool actions: their digital_out / wait_input / wait_s
    steps on the tool's group's controller), straight over ur_rtde."""

    def __init__(self, doc: dict, arms: dict[str, Arm]) -> None:
        self.doc, self.arms = doc, arms
        # Numbers from the parameters ({parameter: id, scale: k}) at their defaults, as on a first start.
        defaults = {p["id"]: p["default"] for p in (doc.get("parameters") or {}).get("items", [])}

        def subst(v: object) -> object:
            if isinstance(v, dict) and set(v) <= {"parameter", "scale"} and "parameter" in v:
                return float(defaults[v["parameter"]]) * float(v.get("scale", 1))
            if isinstance(v, dict):
                return {k: subst(x) for k, x in v.items()}
            if isinstance(v, list):
                return [subst(x) for x in v]
            return v

        self.proc = subst(doc["process"])
        manual = doc["manual"]
        self.configs = {g["name"]: g["configurations"] for g in manual["groups"]}
        self.tools = {t["name"]: t for t in manual["tools"]}
        self.log: list[str] = []

    def run_cycle(self, cycle: int) -> None:
        for op in self.proc["operations"]:
            for step in op["steps"]:
                self.step(step, cycle)

    def step(self, step: dict, cycle: int) -> None:
        group = step.get("group", self.proc["group"])
        self.log.append(f"{group}: {step}")
        if "move_named" in step:
            arm = self.arms[group]
            q = self.configs[group][step["move_named"]]
            assert arm.c.moveJ(q, step.get("speed", self.proc["joint_speed"]), self.proc["joint_acceleration"]), step
        elif "move_pose" in step:
            table = self.proc["poses"][step["move_pose"]]
            pose = np.array(table[(cycle - 1) % len(table)], dtype=float)
            pose[:3] += np.array(step.get("offset", [0] * 6)[:3], dtype=float)
            self._movel(group, pose, step)
        elif "move_relative" in step:
            pose = np.array(self.arms[group].r.getActualTCPPose())
            pose[:3] += np.array(step["move_relative"][:3], dtype=float)
            self._movel(group, pose, step)
        elif "tool" in step:
            tool = self.tools[step["tool"]]
            arm = self.arms[tool["group"]]
            action = next(a for a in tool["actions"] if a["name"] == step["action"])
            for s in action["steps"]:
                if "digital_out" in s:
                    assert arm.io.setStandardDigitalOut(s["digital_out"], s["value"])
                elif "wait_input" in s:
                    n, want = s["wait_input"], s["value"]
                    wait_for(lambda: bool(arm.r.getActualDigitalInputBits() & (1 << n)) == want,
                             s.get("timeout_s", 2) / SPEED + 1.0, what=f"{step['tool']} {step['action']}: DI{n}={want}")
                elif "wait_s" in s:
                    time.sleep(s["wait_s"] / SPEED)
        else:
            raise AssertionError(f"step kind not run here: {step}")

    def _movel(self, group: str, pose: np.ndarray, step: dict) -> None:
        arm = self.arms[group]
        assert arm.c.moveL(list(pose), step.get("speed", self.proc["tcp_speed"]), self.proc["tcp_acceleration"]), \
            f"{group} moveL to {np.round(pose, 4)} failed ({step})"
        wait_for(arm.c.isSteady, 3, what="steady")


def test_hand_over_process_puts_every_cube_in_its_pocket(roscore, start_sim):
    import rospy
    from geometry_msgs.msg import PoseArray
    start_twin(start_sim, env={"ROS_MASTER_URI": roscore})
    if not rospy.core.is_initialized():
        rospy.init_node("sim_test", anonymous=True, disable_signals=True)
    latest: dict[str, PoseArray] = {}
    sub = rospy.Subscriber("/sim/objects", PoseArray, lambda m: latest.__setitem__("m", m), queue_size=2)
    doc = twin_doc()
    # 125 Hz streams (a CB3's rate): four 500 Hz streams of one process would take the sim's time for no gain here.
    arms = {g: Arm(h, 125.0) for g, h in HOSTS.items()}
    runner = ProcessRunner(doc, arms)
    pockets = doc["simulation"]["stations"][1]["pockets"]
    t0 = time.monotonic()
    try:
        wait_for(lambda: "m" in latest, 5, what="/sim/objects")
        assert latest["m"].header.frame_id == "world"  # two arms: the poses are in the world frame
        for cycle in (1, 2, 3):
            runner.run_cycle(cycle)
            time.sleep(0.5)  # the released cube settles; /sim/objects runs at 5 Hz
            stamp = latest["m"].header.stamp
            wait_for(lambda: latest["m"].header.stamp > stamp, 2, what="a fresh /sim/objects")
            cube = latest["m"].poses[cycle - 1]
            x, y, z = cube.position.x, cube.position.y, cube.position.z
            px, py = pockets[cycle - 1]
            print(f"cycle {cycle}: cube at ({x:.4f}, {y:.4f}, {z:.4f}), {time.monotonic() - t0:.1f} s")
            # In the pocket: centred within a few mm, resting on the plate (centre 0.026 m above the table), square.
            assert math.hypot(x - px, y - py) < 0.004, f"cube {cycle} at ({x:.4f}, {y:.4f}), pocket ({px}, {py})"
            assert abs(z - 0.026) < 0.002, f"cube {cycle} at z = {z:.4f}"
            o = cube.orientation
            tilt = math.degrees(2 * math.asin(min(1.0, math.hypot(o.x, o.y))))
            assert tilt < 2.0, f"cube {cycle} tilted {tilt:.1f} deg"
        # Both arms end at home.
        for g, a in arms.items():
            assert np.max(np.abs(np.array(a.r.getActualQ()) - doc["manual"]["groups"][0 if g == "left" else 1]
                                 ["configurations"]["home"])) < 1e-3
            assert a.r.getSafetyMode() == 1, f"{g}: safety mode {a.r.getSafetyMode()}"
    finally:
        print(f"hand-over of 3 cubes: {time.monotonic() - t0:.1f} s wall at speed {SPEED}")
        sub.unregister()
        for a in arms.values():
            a.close()


# ---------------------------------------------------------------------------------------------- devices on ROS
def test_devices_per_arm_on_ros(roscore, start_sim, tmp_path):
    """The twin cell with sensors and streams added: each WrenchStamped topic carries its group's wrist, a stream
    shows a viewpoint of the cell's own (both arms in the render replica), faults name their arm."""
    import rospy
    from cell_msgs.msg import AlarmList
    from cell_msgs.srv import TriggerFault
    from geometry_msgs.msg import WrenchStamped
    from sensor_msgs.msg import CompressedImage
    doc = twin_doc()
    doc["sensors"] = [
        {"title": "Left wrist", "kind": "time-series", "topic": "/twin/left/wrench", "type": WRENCH_TYPE},
        {"title": "Right wrist", "kind": "time-series", "topic": "/twin/right/wrench", "type": WRENCH_TYPE,
         "group": "right"}]
    doc["video"] = {"streams": [{"name": "Hand-over", "topic": "/twin/hand_over/compressed", "view": "hand_over"}]}
    cell = tmp_path / "twin-devices.yaml"
    cell.write_text(yaml.safe_dump(doc))
    sim = start_sim(LEFT, "--cell", str(cell), "--hosts", f"left={LEFT},right={RIGHT}", "--speed", "1",
                    "--camera-size", "96x72", "--camera-rate", "4", "--sensor-rate", "20",
                    env={"ROS_MASTER_URI": roscore})
    wait_for(lambda: _open(RIGHT, 30004), 10, what="right arm's RTDE port")
    if not rospy.core.is_initialized():
        rospy.init_node("sim_test", anonymous=True, disable_signals=True)
    got: dict[str, list] = {"left": [], "right": [], "image": [], "faults": []}
    subs = [rospy.Subscriber("/twin/left/wrench", WrenchStamped, got["left"].append),
            rospy.Subscriber("/twin/right/wrench", WrenchStamped, got["right"].append),
            rospy.Subscriber("/twin/hand_over/compressed", CompressedImage, got["image"].append, buff_size=2 ** 20),
            rospy.Subscriber("/sim/faults", AlarmList, got["faults"].append)]
    r = {g: rtde_receive.RTDEReceiveInterface(h) for g, h in HOSTS.items()}
    try:
        wait_for(lambda: len(got["left"]) > 3 and len(got["right"]) > 3 and got["image"] and got["faults"], 30,
                 what="wrench, image and fault messages")
        left, right = got["left"][-1], got["right"][-1]
        assert (left.header.frame_id, right.header.frame_id) == ("left_ft_sensor", "right_ft_sensor")
        # Each carries its own tool's weight: the gripper (0.7 kg with fingers) is heavier than the vacuum tool.
        fl = np.linalg.norm([left.wrench.force.x, left.wrench.force.y, left.wrench.force.z])
        fr = np.linalg.norm([right.wrench.force.x, right.wrench.force.y, right.wrench.force.z])
        assert fl > fr + 1.0, (fl, fr)
        assert np.linalg.norm(r["left"].getFtRawWrench()[:3]) == pytest.approx(fl, abs=0.5)
        assert np.linalg.norm(r["right"].getFtRawWrench()[:3]) == pytest.approx(fr, abs=0.5)
        img = got["image"][-1]
        assert img.format == "jpeg" and img.header.frame_id == "camera_hand_over" and img.data[:2] == b"\xff\xd8"
        ids = [a.id for a in got["faults"][-1].alarms]
        assert "right.protective_stop" in ids and "left.gripper_fault" in ids and "door_open" in ids
        rospy.wait_for_service("/sim/trigger_fault", 5)
        trigger = rospy.ServiceProxy("/sim/trigger_fault", TriggerFault)
        assert trigger("right.protective_stop").success
        wait_for(lambda: r["right"].getSafetyMode() == 3, 3, what="right protective stop")
        assert r["left"].getSafetyMode() == 1, "the left arm runs on"
        wait_for(lambda: {a.id for a in got["faults"][-1].alarms if a.active} == {"right.protective_stop"}, 3,
                 what="/sim/faults naming the right arm")
        assert trigger("reset").success
        wait_for(lambda: r["right"].getSafetyMode() == 1, 3, what="reset")
    finally:
        for s in subs:
            s.unregister()
        for x in r.values():
            x.disconnect()
    assert "Traceback" not in sim.output()


def test_each_arm_has_its_own_force_guard() -> None:
    """In-process: the right arm driven into the table protective-stops; the left arm runs on undisturbed."""
    from sim import motion
    from sim.cell import Cell, CellOptions
    from sim.cell_file import load_devices
    cell = Cell(CellOptions(devices=load_devices(str(TWIN)), hosts={"left": "127.0.3.17", "right": "127.0.3.18"},
                            ros=False, cameras=False))  # not started: the test ticks the loop itself
    try:
        left, right = cell.controllers["left"], cell.controllers["right"]
        for _ in range(200):
            cell.loop.tick()
        goal = right.snapshot.actual_TCP_pose.copy()
        goal[2] = -0.05  # 5 cm into the table
        right.arm.start(motion.LinearMove(right.arm.q_set, goal, 0.1, 0.5, right.tcp))
        q_left = left.arm.q_set + np.array([0.3, 0, 0, 0, 0, 0])
        left.arm.start(motion.JointMove(left.arm.q_set, q_left, 0.5, 1.0))
        for _ in range(5 * 500):
            cell.loop.tick()
            if right.safety_mode == 3 and not left.arm.busy():
                break
        assert right.safety_mode == 3 and cell.faults.active("right.force_limit")
        assert left.safety_mode == 1 and not cell.faults.active("left.force_limit")
        for _ in range(300):
            cell.loop.tick()
        assert np.max(np.abs(left.snapshot.actual_q - q_left)) < 1e-3
        assert 0.0 < right.snapshot.actual_TCP_pose[2] < 0.05
    finally:
        cell.world.close()
