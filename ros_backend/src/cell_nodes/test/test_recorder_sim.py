"""The flight recorder in the demo cell against the simulated cell: roscore + the sim (UR controller over RTDE) + the
operation-mode, robot driver (manual_node), process, alarms and recorder nodes, all with config/demo-cell.yaml
(its `recorder:` section shortened to 5 s before an alarm and 2 s after). A protective stop during a running
process makes the alarms node raise robot.protective_stop; the recorder saves one MCAP file that the mcap library
reads back with the joint states, the process log and the alarm in it, from the configured seconds before the
alarm on, and that rosbags decodes from the definitions the file carries. Its JSON description's timeline shows
the run, the error and the alarm mode."""
from __future__ import annotations

import json
import os
import time
from pathlib import Path
from typing import Any, Iterator, List

import pytest
import rospy
import yaml
from mcap.reader import make_reader
from mcap_ros1.decoder import DecoderFactory

from cell_nodes.recorder.retention import recordings
from conftest import wait_for
from nodes_helpers import Nodes, client_node
from sim.tests.conftest import SimProcess, sim_env
from test_process_node import Ui, start_process_nodes
from test_process_sim import Joints

HOST = "127.0.0.72"
ROOT = Path(__file__).resolve().parents[4]
BEFORE_S, AFTER_S = 5.0, 2.0


@pytest.fixture(scope="module")
def cell(roscore: str, tmp_path_factory) -> Iterator[dict]:
    doc = yaml.safe_load((ROOT / "config" / "demo-cell.yaml").read_text())
    doc["recorder"] = {**doc["recorder"], "before_s": BEFORE_S, "after_s": AFTER_S}
    base = tmp_path_factory.mktemp("recorder_sim")
    path = base / "cell.yaml"
    path.write_text(yaml.safe_dump(doc))
    env = dict(os.environ, DATA_DIR=str(base / "data"))
    sim = SimProcess(HOST, ["--no-cameras", "--cell", str(path)], sim_env(roscore))
    procs = Nodes()
    ui = joints = None
    try:
        sim.wait_ready()
        client_node("recorder_sim_client")
        from cell_msgs.msg import RobotState
        from test_process_node import Latest
        procs.run("operation_mode", "operation_mode_node", f"_cell_config:={path}", "__name:=recorder_sim_mode")
        procs.run("manual", "manual_node", f"_cell_config:={path}", f"_ur_host:={HOST}", "__name:=recorder_sim_manual")
        procs.run("alarms", "alarms_node", f"_cell_config:={path}", "__name:=recorder_sim_alarms")
        recorder = procs.run("recorder", "recorder_node", f"_cell_config:={path}", "__name:=recorder_sim_recorder", env=env)
        start_process_nodes(procs, path, "recorder_sim")
        ui, joints = Ui(), Joints()
        robot = Latest("/cell/manual/arm/state", RobotState)
        procs.wait_ready("/cell/process/start", "/cell/alarms/reset", "/cell/recorder/save", what="the nodes' services")
        wait_for(lambda: robot.msg is not None and robot.msg.connected and joints.msg is not None, 15,
                 what="the driver connected to the sim")
        robot.sub.unregister()
        wait_for(lambda: ui.state.msg is not None and ui.state.msg.ready, 10, what="the process client ready")
        yield {"ui": ui, "joints": joints, "dir": base / "data" / "recordings", "recorder": recorder}
    finally:
        if joints is not None:
            joints.sub.unregister()
        if ui is not None:
            ui.close()
        procs.stop()
        sim.stop()
        procs.check()
        assert "Traceback" not in sim.output(), sim.output()[-3000:]


def test_a_fault_during_a_run_is_saved_as_one_mcap_file_with_what_led_to_it(cell: dict) -> None:
    from cell_msgs.srv import TriggerFault
    ui, joints, directory = cell["ui"], cell["joints"], cell["dir"]
    trigger = rospy.ServiceProxy("/sim/trigger_fault", TriggerFault)
    assert [r.name for r in recordings(str(directory))] == []
    started = time.time()
    assert ui.start(cycles=1).success
    # The run goes on for longer than the recorder keeps before an alarm.
    wait_for(lambda: time.time() - started > BEFORE_S + 1 and ui.state.msg.step.startswith("Move to")
             and joints.speed() > 0.05, 60, what="a move running after the first seconds of the run")
    try:
        at = time.time()
        assert trigger("protective_stop").success
        ui.wait_state("error", 10)
        wait_for(lambda: len(recordings(str(directory))) == 1, AFTER_S + 10, what="one recording")
        [saved] = recordings(str(directory))
        assert "-alarm-device-protective-stop" in saved.name, saved.name
        path = directory / saved.name

        # --- the mcap library, decoding with the definitions in the file
        with open(path, "rb") as f:
            reader = make_reader(f, decoder_factories=[DecoderFactory()])
            summary = reader.get_summary()
            assert summary is not None and all(s.encoding == "ros1msg" for s in summary.schemas.values())
            assert reader.get_header().profile == "ros1"
            read = [(c.topic, m.log_time / 1e9, msg) for _, c, m, msg in reader.iter_decoded_messages()]
            metadata = {m.name: m.metadata for m in reader.iter_metadata()}
        assert metadata["recording"]["reason"].startswith("alarm device.protective_stop")
        assert metadata["recording"]["alarms"].split(",")[0] == "device.protective_stop"
        js = [t for topic, t, _ in read if topic == "/joint_states"]
        # The configured seconds before the alarm, and those after it, nothing missing at 125 Hz.
        assert js[0] <= at - BEFORE_S + 0.2 and js[-1] >= at + AFTER_S - 0.5, (js[0] - at, js[-1] - at)
        assert max(b - a for a, b in zip(js, js[1:])) < 0.25
        logs = [e.text for topic, _, msg in read if topic == "/cell/process/log" for e in msg.entries]
        # The run's end is in it, whichever stopped the run first: the move the protective stop refused, or the
        # alarm mode the alarms node switched to (CI saw both orders).
        assert any("protective stop" in t or "the cell went into alarm" in t for t in logs), logs[-5:]
        assert any(a.id == "device.protective_stop" and a.active for topic, _, msg in read if topic == "/cell/alarms/list"
                   for a in msg.alarms)
        states = [msg.state for topic, _, msg in read if topic == "/cell/process/state"]
        assert "running" in states and states[-1] == "error", states

        # --- rosbags: its own ROS 1 deserializer, from the definitions the file carries
        decoded = by_rosbags(path)
        assert decoded["/joint_states"][0].name == read[[t for t, _, _ in read].index("/joint_states")][2].name
        assert len(decoded["/joint_states"]) == len(js)
        assert any(a.id == "device.protective_stop" for m in decoded["/cell/alarms/list"] for a in m.alarms)

        # --- the description the Recordings page reads
        about = json.loads(path.with_suffix(".json").read_text())
        lanes = {lane["id"]: [c["text"] for c in lane["changes"]] for lane in about["timeline"]["lanes"]}
        assert any(t.startswith("running · Move to") for t in lanes["process"]), lanes
        last = lanes["process"][-1]  # the run's end, either way (above)
        assert last.startswith("error · ") and ("protective stop" in last or "the cell went into alarm" in last), lanes
        assert any("device.protective_stop" in t for t in lanes["alarms"]), lanes
        assert "running" in lanes["mode"] and lanes["mode"][-1] == "alarm", lanes
        assert about["size"] == saved.size and about["messages"] == len(read)
    finally:
        trigger("reset")
        rospy.ServiceProxy("/cell/alarms/reset", __import__("std_srvs.srv", fromlist=["Trigger"]).Trigger)()


def by_rosbags(path: Path) -> dict[str, List[Any]]:
    """Every message of the file, deserialized by rosbags' ROS 1 typestore from the file's own definitions.
    (rosbags reads MCAP files of the ROS 2 profile only; the ROS 1 messages are decoded with its ros1 serde.)"""
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore
    store = get_typestore(Stores.EMPTY)
    out: dict[str, List[Any]] = {}
    with open(path, "rb") as f:
        reader = make_reader(f)
        for schema, channel, message in reader.iter_messages():
            package, _, name = schema.name.partition("/")
            typename = f"{package}/msg/{name}"           # rosbags' names for types, ROS 1 or 2
            if typename not in store.types:
                store.register(get_types_from_msg(schema.data.decode(), typename))
            out.setdefault(channel.topic, []).append(store.deserialize_ros1(message.data, typename))
    return out
