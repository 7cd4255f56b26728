"""The flight recorder's core without ROS running (cell_nodes.recorder): the ring's bounds, an MCAP file that the
mcap library reads back into the very messages (rospy's own serialization, definitions embedded), atomic saves, and
the recordings directory's retention."""
from __future__ import annotations

import io
import os
from pathlib import Path
from typing import Any, List

import pytest
from mcap.reader import make_reader
from mcap_ros1.decoder import DecoderFactory
from sensor_msgs.msg import JointState
from std_msgs.msg import String

from cell_msgs.msg import Alarm, AlarmList
from cell_nodes.recorder import mcap_file, retention
from cell_nodes.recorder.mcap_file import write_mcap
from cell_nodes.recorder.ring import OVERHEAD_BYTES, RawMessage, Ring, Schema

S = 1_000_000_000


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
    (tmp_path / "notes.txt").write_text("not a recording")
    assert retention.prune(str(tmp_path), max_count=4, max_bytes=10_000) == ["r0.mcap", "r1.mcap"]
    assert [r.name for r in retention.recordings(str(tmp_path))] == ["r2.mcap", "r3.mcap", "r4.mcap", "r5.mcap"]
    assert sorted(os.listdir(tmp_path)) == ["notes.txt", "r2.mcap", "r3.mcap", "r4.mcap", "r5.mcap"]
    assert retention.prune(str(tmp_path), max_count=10, max_bytes=250) == ["r2.mcap", "r3.mcap"]
    recording(tmp_path, "big.mcap", 1000, 2000)                  # the newest, alone over the budget: it stays
    assert retention.prune(str(tmp_path), max_count=10, max_bytes=250) == ["r4.mcap", "r5.mcap"]
    assert [r.name for r in retention.recordings(str(tmp_path))] == ["big.mcap"]
    assert retention.prune(str(tmp_path / "none"), 1, 1) == [] and retention.recordings(str(tmp_path / "none")) == []
