"""The flight recorder's core without ROS running (cell_nodes.recorder): the ring's bounds, an MCAP file that the
mcap library reads back into the very messages (rospy's own serialization, definitions embedded), atomic saves, and
the recordings directory's retention."""
from __future__ import annotations

import io
import json
import os
from pathlib import Path
from typing import Any, List

import pytest
import yaml
from mcap.reader import make_reader
from mcap_ros1.decoder import DecoderFactory
from sensor_msgs.msg import JointState
from std_msgs.msg import String

from cell_msgs.msg import Alarm, AlarmList
from cell_nodes.recorder import mcap_file, retention
from cell_nodes.recorder.config import RecorderConfigError, parse_recorder
from cell_nodes.recorder.core import Recorder, RecorderConfig
from cell_nodes.recorder.mcap_file import write_mcap
from cell_nodes.recorder.ring import OVERHEAD_BYTES, RawMessage, Ring, Schema
from cell_nodes.recorder.sidecar import sidecar_path
from cell_nodes.recorder.timeline import Change, Timeline, alarms_text, process_text

S = 1_000_000_000
ROOT = Path(__file__).resolve().parents[4]


def raw(topic: str, msg: Any, t_ns: int) -> RawMessage:
    """What the node builds from a rospy.AnyMsg: the bytes on the wire and the connection header's type fields."""
    buf = io.BytesIO()
    msg.serialize(buf)
    return RawMessage(topic, Schema(msg._type, msg._md5sum, msg._full_text), buf.getvalue(), t_ns)


def text(n: int, t_ns: int, size: int = 10) -> RawMessage:
    return raw("/t", String(data=str(n).rjust(size, "x")), t_ns)


# ---------------------------------------------------------------------------------------------- ring
def test_the_ring_keeps_the_last_seconds() -> None:
    ring = Ring(seconds=2.0, max_bytes=1 << 20)
    for i in range(50):                                          # one message every 0.1 s for 5 s
        ring.add(text(i, i * S // 10))
    kept = ring.window(0, 10 * S)
    assert [m.data for m in kept] == [text(i, 0).data for i in range(29, 50)]   # 2.9 s .. 4.9 s: the last 2 s
    st = ring.stats()
    assert (st.messages, st.oldest_ns, st.newest_ns, st.dropped) == (21, 29 * S // 10, 49 * S // 10, 29)
    ring.expire(10 * S)                                          # a quiet cell forgets too
    assert ring.stats().messages == 0 and ring.stats().bytes == 0


def test_the_ring_keeps_within_its_bytes_whatever_the_message_size() -> None:
    one = text(0, 0, size=1000).cost
    ring = Ring(seconds=3600, max_bytes=10 * one)
    for i in range(25):
        assert ring.add(text(i, i, size=1000))
        assert ring.stats().bytes <= 10 * one
    assert ring.stats().messages == 10 and ring.stats().dropped == 15
    # a flood of empty messages is bounded by their overhead
    for i in range(10_000):
        ring.add(raw("/e", String(), 100 + i))
    assert ring.stats().bytes <= 10 * one and ring.stats().messages <= 10 * one // OVERHEAD_BYTES
    # one message larger than the whole ring is refused, and nothing else is lost for it
    before = ring.stats().messages
    assert not ring.add(text(1, 20_000, size=20 * one))
    assert ring.stats().messages == before and ring.stats().refused == 1


def test_a_window_is_a_copy_in_time_order() -> None:
    ring = Ring(seconds=60, max_bytes=1 << 20)
    for i in range(10):
        ring.add(text(i, i * S))
    w = ring.window(3 * S, 6 * S)
    assert [m.t_ns for m in w] == [3 * S, 4 * S, 5 * S, 6 * S]
    ring.add(text(99, 11 * S))
    assert len(w) == 4


def test_a_window_carries_in_each_topics_last_value_from_before_it() -> None:
    ring = Ring(seconds=10, max_bytes=1 << 20)
    ring.add(raw("/cell/mode", String(data="running"), 1 * S))       # latched, once: long gone from the ring
    for i in range(20, 40):
        ring.add(text(i, i * S))
    assert ring.stats().oldest_ns == 29 * S
    w = ring.window(32 * S, 34 * S, carry_in=True)
    assert [(m.topic, m.t_ns, m.received_ns) for m in w] == [
        ("/cell/mode", 32 * S, 1 * S), ("/t", 32 * S, 31 * S), ("/t", 32 * S, None), ("/t", 33 * S, None),
        ("/t", 34 * S, None)]
    assert w[0].data == raw("/cell/mode", String(data="running"), 0).data
    assert [m.t_ns for m in ring.window(32 * S, 34 * S)] == [32 * S, 33 * S, 34 * S]   # without: only what came


@pytest.mark.parametrize("seconds, max_bytes", [(0, 10), (-1, 10), (1, 0)])
def test_a_ring_without_room_is_refused(seconds: float, max_bytes: int) -> None:
    with pytest.raises(ValueError):
        Ring(seconds, max_bytes)


# ---------------------------------------------------------------------------------------------- MCAP
def messages() -> List[RawMessage]:
    js = JointState(name=["shoulder_pan_joint", "elbow_joint"], position=[0.5, -1.25], velocity=[0.0, 0.1])
    alarm = AlarmList()
    alarm.alarms.append(Alarm(id="device.gripper", severity=Alarm.ERROR, text="gripper does not close",
                              source="device"))
    return ([raw("/joint_states", js, 10 * S + i * S // 100) for i in range(5)]
            + [raw("/cell/alarms", alarm, 11 * S)] + [raw("/joint_states", js, 11 * S + 1)])


def test_an_mcap_file_reads_back_into_the_same_messages_with_their_definitions(tmp_path: Path) -> None:
    path = tmp_path / "rec.mcap"
    size = write_mcap(str(path), messages(), {"reason": "alarm SIM_FAULT", "alarm_ns": str(11 * S)})
    assert size == path.stat().st_size > 0
    with open(path, "rb") as f:                                  # decoded from the definitions in the file alone
        read = [(c.topic, m.log_time, msg) for _, c, m, msg in
                make_reader(f, decoder_factories=[DecoderFactory()]).iter_decoded_messages()]
    assert [t for t, _, _ in read] == ["/joint_states"] * 5 + ["/cell/alarms", "/joint_states"]
    assert [t for _, t, _ in read] == [m.t_ns for m in messages()]
    joints, alarms = read[0][2], read[5][2]
    assert list(joints.name) == ["shoulder_pan_joint", "elbow_joint"] and list(joints.position) == [0.5, -1.25]
    assert alarms.alarms[0].id == "device.gripper" and alarms.alarms[0].severity == Alarm.ERROR
    with open(path, "rb") as f:
        reader = make_reader(f)
        summary = reader.get_summary()
        assert reader.get_header().profile == mcap_file.PROFILE
        schemas = {s.name: s for s in summary.schemas.values()}
        assert set(schemas) == {"sensor_msgs/JointState", "cell_msgs/AlarmList"}
        assert schemas["cell_msgs/AlarmList"].encoding == "ros1msg"
        assert b"MSG: cell_msgs/Alarm" in schemas["cell_msgs/AlarmList"].data        # dependencies embedded
        assert {c.topic: c.message_encoding for c in summary.channels.values()} == {
            "/joint_states": "ros1", "/cell/alarms": "ros1"}
        assert summary.statistics.message_count == 7
        [meta] = list(reader.iter_metadata())
        assert (meta.name, meta.metadata["reason"]) == ("recording", "alarm SIM_FAULT")


def test_a_failed_save_leaves_no_file_and_no_temp_file(tmp_path: Path) -> None:
    class Boom(Exception):
        pass

    def broken():
        yield messages()[0]
        raise Boom()

    with pytest.raises(Boom):
        write_mcap(str(tmp_path / "rec.mcap"), broken())
    assert os.listdir(tmp_path) == []
    # an older recording of that name stays whole
    write_mcap(str(tmp_path / "rec.mcap"), messages())
    before = (tmp_path / "rec.mcap").read_bytes()
    with pytest.raises(Boom):
        write_mcap(str(tmp_path / "rec.mcap"), broken())
    assert os.listdir(tmp_path) == ["rec.mcap"] and (tmp_path / "rec.mcap").read_bytes() == before


# ---------------------------------------------------------------------------------------------- retention
def recording(directory: Path, name: str, size: int, mtime: float) -> None:
    p = directory / name
    p.write_bytes(b"x" * size)
    os.utime(p, (mtime, mtime))


def test_retention_deletes_the_oldest_past_the_count_or_the_bytes_never_the_newest(tmp_path: Path) -> None:
    for i in range(6):
        recording(tmp_path, f"r{i}.mcap", 100, 1000 + i)
    (tmp_path / f"{mcap_file.TEMP_PREFIX}cut.mcap").write_bytes(b"torn")     # a save cut by a power loss
    (tmp_path / f"{mcap_file.TEMP_PREFIX}cut.json").write_bytes(b"{")
    (tmp_path / "r0.json").write_text("{}")                                    # descriptions go with their files
    (tmp_path / "r2.json").write_text("{}")
    (tmp_path / "notes.txt").write_text("not a recording")
    assert retention.prune(str(tmp_path), max_count=4, max_bytes=10_000) == ["r0.mcap", "r1.mcap"]
    assert [r.name for r in retention.recordings(str(tmp_path))] == ["r2.mcap", "r3.mcap", "r4.mcap", "r5.mcap"]
    assert sorted(os.listdir(tmp_path)) == ["notes.txt", "r2.json", "r2.mcap", "r3.mcap", "r4.mcap", "r5.mcap"]
    os.unlink(tmp_path / "r2.json")
    assert retention.prune(str(tmp_path), max_count=10, max_bytes=250) == ["r2.mcap", "r3.mcap"]
    recording(tmp_path, "big.mcap", 1000, 2000)                  # the newest, alone over the budget: it stays
    assert retention.prune(str(tmp_path), max_count=10, max_bytes=250) == ["r4.mcap", "r5.mcap"]
    assert [r.name for r in retention.recordings(str(tmp_path))] == ["big.mcap"]
    assert retention.prune(str(tmp_path / "none"), 1, 1) == [] and retention.recordings(str(tmp_path / "none")) == []


# ---------------------------------------------------------------------------------------------- recorder
def recorder(tmp_path: Path, **kw: Any) -> Recorder:
    cfg = RecorderConfig(directory=str(tmp_path / "recordings"), before_s=10, after_s=5, **kw)
    return Recorder(cfg, clock_ns=lambda: 0)


def joints(rec: Recorder, seconds: range) -> None:
    for t in seconds:                                            # one joint state a second
        rec.add(raw("/joint_states", JointState(name=["j"], position=[float(t)]), t * S))


def test_a_new_error_alarm_saves_the_seconds_before_it_and_after_it(tmp_path: Path) -> None:
    rec = recorder(tmp_path)
    joints(rec, range(0, 100))
    assert rec.alarms([("robot.protective_stop", Alarm.WARNING, "slow down")], 100 * S) is None   # below error
    p = rec.alarms([("robot.protective_stop", Alarm.ERROR, "Protective stop")], 100 * S)
    assert p is not None and p.reason == "alarm robot.protective_stop: Protective stop"
    joints(rec, range(100, 108))                                 # the save runs late: 2 s past its end
    assert rec.save_due(104 * S) is None                         # its 5 s after are not over yet
    saved = rec.save_due(107 * S)
    assert saved is not None and saved.name == "19700101T000140.000Z-alarm-robot-protective-stop-protective-stop.mcap"
    assert (saved.start_ns, saved.end_ns, saved.messages) == (90 * S, 105 * S, 17)
    with open(saved.path, "rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        read = [(m.log_time, m.publish_time, msg.position[0]) for _, _, m, msg in reader.iter_decoded_messages()]
    # 10 s before the alarm to 5 s after, and the value at the start (received at 89 s) logged at the start
    assert read == [(90 * S, 89 * S, 89.0)] + [(t * S, t * S, float(t)) for t in range(90, 106)]
    assert rec.save_due(200 * S) is None                         # written once


def test_each_recording_has_a_description_with_its_topics_and_timeline(tmp_path: Path) -> None:
    rec = recorder(tmp_path)
    rec.mark("mode", "running", 50 * S)                          # before the window: carried in at its start
    rec.mark("process", "running · Move to part 1", 91 * S)
    joints(rec, range(85, 100))
    rec.mark("process", "running · Move to part 1", 92 * S)      # the same again: no change
    rec.mark("alarms", "robot.protective_stop: Protective stop", 100 * S)
    rec.alarms([("robot.protective_stop", Alarm.ERROR, "Protective stop")], 100 * S)
    rec.mark("process", "error · Move failed", 101 * S)
    rec.mark("mode", "alarm", 101 * S)
    rec.mark("mode", "idle", 106 * S)                            # after the window
    saved = rec.save_due(105 * S)
    assert saved is not None and saved.sidecar_error == ""
    d = json.loads(Path(sidecar_path(saved.path)).read_text())
    assert (d["name"], d["reason"], d["alarms"]) == (saved.name, "alarm robot.protective_stop: Protective stop",
                                                     ["robot.protective_stop"])
    assert (d["at_ms"], d["start_ms"], d["end_ms"], d["duration_s"], d["messages"]) == (100_000, 90_000, 105_000, 15, 11)
    assert d["size"] == os.path.getsize(saved.path)
    assert d["topics"] == [{"topic": "/joint_states", "type": "sensor_msgs/JointState", "count": 11}]
    lanes = {lane["id"]: [(c["t_ms"], c["text"]) for c in lane["changes"]] for lane in d["timeline"]["lanes"]}
    assert [lane["title"] for lane in d["timeline"]["lanes"]] == ["Alarms", "Process", "Operation mode"]
    assert lanes == {"alarms": [(100_000, "robot.protective_stop: Protective stop")],
                     "process": [(91_000, "running · Move to part 1"), (101_000, "error · Move failed")],
                     "mode": [(90_000, "running"), (101_000, "alarm")]}


def test_a_timeline_lane_forgets_what_is_older_than_its_span_but_its_value_then() -> None:
    tl = Timeline(seconds=10, max_changes=100)
    for t in range(0, 30, 2):
        assert tl.mark("mode", t * S, f"m{t}")
    assert not tl.mark("mode", 31 * S, "m28")
    w = tl.window(20 * S, 30 * S)["mode"]
    assert w == [Change(20 * S, "m20"), Change(22 * S, "m22"), Change(24 * S, "m24"), Change(26 * S, "m26"),
                 Change(28 * S, "m28")]
    assert tl.window(0, 30 * S)["mode"][0] == Change(16 * S, "m16")  # the value at the span's start (18 s) kept
    assert tl.window(0, 30 * S)["alarms"] == []
    few = Timeline(seconds=1000, max_changes=3)                  # a flapping value is bounded by count too
    for t in range(10):
        few.mark("alarms", t * S, str(t))
    assert [c.text for c in few.window(0, 100 * S)["alarms"]] == ["7", "8", "9"]


def test_an_alarm_still_active_does_not_record_again_others_join_the_waiting_recording(tmp_path: Path) -> None:
    rec = recorder(tmp_path)
    a = ("device.gripper", Alarm.ERROR, "gripper does not close")
    b = ("force.limit", Alarm.ERROR, "force over the limit")
    assert rec.alarms([a], 10 * S) is not None
    assert rec.alarms([a, b], 12 * S) is None                    # joins: one recording, both alarms in it
    assert rec.pending is not None and rec.pending.alarms == ["device.gripper", "force.limit"]
    assert rec.save_due(15 * S) is not None
    assert rec.alarms([a, b], 20 * S) is None                    # still the same alarms: nothing new
    assert rec.alarms([b], 21 * S) is None                       # one cleared
    assert rec.alarms([a, b], 22 * S) is not None                # and back: a new recording
    # by hand, with no alarm
    rec2 = recorder(tmp_path / "2")
    assert rec2.request("saved by engineer", 50 * S).reason == "saved by engineer"
    assert rec2.save_due(55 * S).name.endswith("-saved-by-engineer.mcap")


def test_recordings_beyond_the_count_are_deleted_oldest_first(tmp_path: Path) -> None:
    rec = recorder(tmp_path, max_count=2)
    names = []
    for i in range(3):
        rec.request(f"save {i}", (100 + 10 * i) * S)
        saved = rec.save_due((105 + 10 * i) * S)
        names.append(saved.name)
        os.utime(saved.path, (1000 + i, 1000 + i))              # file times in save order, whatever the clock
    assert saved.deleted == (names[0],)                          # the third save made room
    assert [r.name for r in retention.recordings(rec.config.directory)] == names[1:]


# ---------------------------------------------------------------------------------------------- the cell file
def cell(name: str) -> dict:
    return yaml.safe_load((ROOT / "config" / name).read_text())


def test_the_default_topics_come_from_the_rest_of_the_cell_file() -> None:
    demo = parse_recorder(cell("demo-cell.yaml"), {"DATA_DIR": "/srv/cell"})
    assert demo.topics == ["/joint_states", "/cell/manual/arm/state", "/cell/process/state", "/cell/process/log",
                           "/cell/alarms/list", "/cell/mode", "/cell/wrench", "/rosout_agg"]
    assert demo.config.directory == "/srv/cell/recordings"
    assert (demo.config.before_s, demo.config.after_s, demo.config.max_bytes, demo.config.max_count,
            demo.config.min_severity) == (120, 10, 64 * 2**20, 20, Alarm.ERROR)
    iiwa = cell("iiwa-cell.yaml")
    iiwa["recorder"] = {}
    [group] = iiwa["manual"]["groups"]
    assert parse_recorder(iiwa, {"DATA_DIR": "/d"}).topics[0] == group["ros_control"]["joint_states"]
    twin = cell("twin-arm-cell.yaml")
    twin["recorder"] = {"topics": ["/joint_states"], "severity": "warning", "directory": "/var/rec"}
    t = parse_recorder(twin, {})
    assert t.topics == ["/joint_states", "/cell/alarms/list"]        # the alarm list always: it says why
    assert (t.config.min_severity, t.config.directory) == (Alarm.WARNING, "/var/rec")


@pytest.mark.parametrize("section, message", [
    ("yes", "recorder: expected a mapping"),
    ({"before_s": 0}, "recorder.before_s: expected a number from 1 to 3600, got 0"),
    ({"after_s": True}, "recorder.after_s: expected a number"),
    ({"memory_mb": float("nan")}, "recorder.memory_mb"),
    ({"severity": "fatal"}, "recorder.severity: expected one of warning, error, got 'fatal'"),
    ({"topics": ["joint_states"]}, "recorder.topics: expected a list of global ROS names"),
    ({"directory": "recordings"}, "recorder.directory: expected an absolute path, got 'recordings'"),
    ({"decimate_s": {"/cam": 0}}, "recorder.decimate_s: expected global ROS names mapped to seconds"),
    ({"decimate_s": ["/cam"]}, "recorder.decimate_s"),
])
def test_a_section_the_node_cannot_use_names_the_field(section: Any, message: str) -> None:
    doc = cell("demo-cell.yaml")
    doc["recorder"] = section
    with pytest.raises(RecorderConfigError) as e:
        parse_recorder(doc, {"DATA_DIR": "/d"})
    assert str(e.value).startswith(message), str(e.value)


def test_without_data_dir_or_directory_there_is_nowhere_to_record() -> None:
    with pytest.raises(RecorderConfigError, match="set DATA_DIR"):
        parse_recorder(cell("demo-cell.yaml"), {})


def test_lane_values_say_what_an_engineer_reads() -> None:
    assert alarms_text([("z.b", "second"), ("a.a", "first")]) == "a.a: first; z.b: second"
    assert alarms_text([]) == ""
    assert process_text("running", "Move to part 2 (approach)", "") == "running · Move to part 2 (approach)"
    assert process_text("error", "Move to part 2", "Move failed: timeout") == "error · Move failed: timeout"
    assert process_text("idle", "", "3 cycles done") == "idle"


def test_a_decimated_topic_keeps_one_message_per_its_seconds_the_others_all(tmp_path: Path) -> None:
    rec = recorder(tmp_path, decimate_s={"/camera": 1.0})
    kept = [rec.add(raw("/camera", String(data=f"frame {i}"), i * S // 10)) for i in range(35)]   # 10 Hz for 3.5 s
    assert [i for i, k in enumerate(kept) if k] == [0, 10, 20, 30]
    assert rec.decimated == 31
    assert all(rec.add(text(i, i * S // 10)) for i in range(35))                                  # not decimated
    assert rec.ring.stats().messages == 4 + 35


def test_decimated_topics_are_recorded_without_being_listed() -> None:
    demo = cell("demo-cell.yaml")
    setup = parse_recorder({**demo, "recorder": {"decimate_s": {"/cell/camera/global/image/compressed": 2}}},
                           {"DATA_DIR": "/tmp/x"})
    assert setup.config.decimate_s == {"/cell/camera/global/image/compressed": 2.0}
    assert setup.topics[-1] == "/cell/camera/global/image/compressed" and "/cell/alarms/list" in setup.topics
