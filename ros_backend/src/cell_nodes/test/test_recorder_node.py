"""The recorder node on a live roscore: `rosrun cell_nodes recorder_node` with a cell file whose `recorder:` section
keeps 3 s before an alarm and 1 s after, its own DATA_DIR. This test publishes joint states at 50 Hz and the alarm
list as the alarms node does; a new error alarm makes one MCAP file in $DATA_DIR/recordings with the joint states of
the seconds before it and the alarm list itself, decoded from the definitions in the file; an alarm that stays
active makes no second file; /cell/recorder/save makes one by hand. A cell file with a bad section stops the node
at once, naming the field."""
from __future__ import annotations

import json
import os
import threading
import time
from pathlib import Path
from typing import Any, Iterator, List, Tuple

import pytest
import rospy
import yaml
from mcap.reader import make_reader
from mcap_ros1.decoder import DecoderFactory

from cell_nodes.recorder.retention import recordings
from conftest import wait_for
from nodes_helpers import Nodes, client_node

ROOT = Path(__file__).resolve().parents[4]
TAG = "recorder_test"
ALARMS = "/cell/alarms/list"


def finished(directory: Path) -> List[str]:
    """The recordings written (not a save's temp file while it is being written)."""
    return [r.name for r in recordings(str(directory))]


def decoded(path: Path) -> List[Tuple[str, int, Any]]:
    with open(path, "rb") as f:
        return [(c.topic, m.log_time, msg) for _, c, m, msg in
                make_reader(f, decoder_factories=[DecoderFactory()]).iter_decoded_messages()]


@pytest.fixture(scope="module")
def recorder(roscore: str, tmp_path_factory) -> Iterator[dict]:
    from cell_msgs.msg import AlarmList
    from sensor_msgs.msg import JointState
    doc = yaml.safe_load((ROOT / "config" / "demo-cell.yaml").read_text())
    doc["recorder"] = {"before_s": 3, "after_s": 1}
    base = tmp_path_factory.mktemp("recorder")
    path = base / "cell.yaml"
    path.write_text(yaml.safe_dump(doc))
    data_dir = base / "data"
    env = dict(os.environ, DATA_DIR=str(data_dir), PYTHONUNBUFFERED="1")
    client_node(f"{TAG}_client")
    joints = rospy.Publisher("/joint_states", JointState, queue_size=50)
    from cell_msgs.msg import OperationMode, ProcessState, RecorderState
    alarms = rospy.Publisher(ALARMS, AlarmList, queue_size=5, latch=True)
    mode = rospy.Publisher("/cell/mode", OperationMode, queue_size=5, latch=True)
    process = rospy.Publisher("/cell/process/state", ProcessState, queue_size=5, latch=True)
    states: List[Any] = []
    state_sub = rospy.Subscriber("/cell/recorder/state", RecorderState, states.append)
    stop = threading.Event()
    sent: List[float] = []

    def publish() -> None:
        while not stop.wait(0.02):
            t = time.time()
            joints.publish(JointState(name=["shoulder_pan_joint"], position=[t % 1000]))
            sent.append(t)

    pump = threading.Thread(target=publish, daemon=True)
    pump.start()
    nodes = Nodes()
    node = nodes.run("recorder", "recorder_node", f"_cell_config:={path}", f"__name:={TAG}", env=env)
    try:
        nodes.wait_ready("/cell/recorder/save", what="the recorder's save service")
        yield {"dir": data_dir / "recordings", "alarms": alarms, "sent": sent, "node": node, "mode": mode,
               "process": process, "states": states}
    finally:
        stop.set()
        pump.join(2)
        nodes.stop()
        print(f"\nrecorder log:\n{node.tail()}")
        nodes.check()
        for x in (joints, alarms, mode, process, state_sub):
            x.unregister()


def alarm_list(*active: str) -> Any:
    from cell_msgs.msg import Alarm, AlarmList
    return AlarmList(alarms=[Alarm(id=a, text=f"{a} happened", severity=Alarm.ERROR, active=True, since=rospy.Time.now())
                             for a in active])


def test_a_new_error_alarm_saves_the_seconds_before_it_as_mcap(recorder: dict) -> None:
    from cell_msgs.msg import OperationMode, ProcessState
    states = recorder["states"]
    wait_for(lambda: states and states[-1].last_saved == "" and states[-1].pending == "", 10, what="the first state")
    recorder["alarms"].publish(alarm_list())
    recorder["mode"].publish(OperationMode(mode="running", source="test", stamp=rospy.Time.now()))
    recorder["process"].publish(ProcessState(state="running", step="Move to part 1"))
    wait_for(lambda: len(recorder["sent"]) > 200, 10, what="4 s of joint states")    # more than `before` s
    at = time.time()
    recorder["alarms"].publish(alarm_list("device.gripper"))
    wait_for(lambda: states[-1].pending == "alarm device.gripper: device.gripper happened", 5, what="a pending save")
    assert abs(states[-1].pending_until.to_sec() - (at + 1)) < 0.5                    # `after` s from the alarm
    recorder["mode"].publish(OperationMode(mode="alarm", source="safety", stamp=rospy.Time.now()))
    wait_for(lambda: len(finished(recorder["dir"])) == 1, 10, what="one recording")
    [name] = finished(recorder["dir"])
    wait_for(lambda: states[-1].last_saved == name, 5, what="the state naming the recording")
    assert (states[-1].pending, states[-1].saved_count, states[-1].error) == ("", 1, "")
    about = json.loads((recorder["dir"] / name.replace(".mcap", ".json")).read_text())
    lanes = {lane["id"]: [c["text"] for c in lane["changes"]] for lane in about["timeline"]["lanes"]}
    assert lanes == {"alarms": ["", "device.gripper: device.gripper happened"], "process": ["running · Move to part 1"],
                     "mode": ["running", "alarm"]}
    assert about["reason"] == "alarm device.gripper: device.gripper happened" and about["alarms"] == ["device.gripper"]
    assert {t["topic"] for t in about["topics"]} >= {"/joint_states", ALARMS, "/cell/mode", "/cell/process/state"}
    assert name.endswith("-alarm-device-gripper-device-gripper-happened.mcap")
    read = decoded(recorder["dir"] / name)
    stamps = [t / 1e9 for topic, t, _ in read if topic == "/joint_states"]
    # from `before` (3 s) ahead of the alarm to `after` (1 s) past it, nothing missing at 50 Hz
    assert at - 3.1 < stamps[0] < at - 2.8 and at + 0.8 < stamps[-1] < at + 1.2
    assert len(stamps) > 0.9 * 4 * 50
    assert all(b - a < 0.2 for a, b in zip(stamps, stamps[1:]))
    assert any(topic == ALARMS and [a.id for a in msg.alarms] == ["device.gripper"] for topic, _, msg in read)
    assert "recording saved" in recorder["node"].output()
    # still active a while later: no second recording
    recorder["alarms"].publish(alarm_list("device.gripper"))
    time.sleep(1.5)
    assert len(finished(recorder["dir"])) == 1


def test_save_by_hand(recorder: dict) -> None:
    from std_srvs.srv import Trigger
    before = set(finished(recorder["dir"]))
    answer = rospy.ServiceProxy("/cell/recorder/save", Trigger)()
    assert answer.success and "saved by hand" in answer.message
    wait_for(lambda: len(set(finished(recorder["dir"])) - before) == 1, 10, what="the recording saved by hand")
    [name] = set(finished(recorder["dir"])) - before
    assert name.endswith("-saved-by-hand.mcap") and any(t == "/joint_states" for t, _, _ in decoded(recorder["dir"] / name))


def test_a_bad_section_stops_the_node_naming_the_field(roscore: str, tmp_path: Path) -> None:
    doc = yaml.safe_load((ROOT / "config" / "demo-cell.yaml").read_text())
    doc["recorder"] = {"before_s": "two minutes"}
    path = tmp_path / "cell.yaml"
    path.write_text(yaml.safe_dump(doc))
    node = Nodes().run("recorder-bad", "recorder_node", f"_cell_config:={path}", f"__name:={TAG}_bad",
                       env=dict(os.environ, DATA_DIR=str(tmp_path)))
    assert node.proc.wait(timeout=15) == 2
    assert "recorder.before_s: expected a number from 1 to 3600, got 'two minutes'" in node.output()
    node.stop()
