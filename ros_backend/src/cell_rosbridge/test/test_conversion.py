"""Message conversion for every ROS 1 field kind, JSON and CBOR forms, and precise errors."""
from __future__ import annotations

import base64
import math
import struct

import cbor2
import genpy
import pytest
import std_msgs.msg as std
import sensor_msgs.msg as sensor
import geometry_msgs.msg as geo

from cell_rosbridge import conversion, encoding
from cell_rosbridge.conversion import ConversionError


def test_every_primitive_roundtrips_through_json() -> None:
    for cls, value in [(std.Bool, True), (std.Int8, -128), (std.UInt8, 255), (std.Int16, -32768),
                       (std.UInt16, 65535), (std.Int32, -2**31), (std.UInt32, 2**32 - 1),
                       (std.Int64, -2**63), (std.UInt64, 2**64 - 1), (std.Float32, 1.5),
                       (std.Float64, -2.25), (std.String, "hé ✓"), (std.Char, 200), (std.Byte, -5)]:
        wire = conversion.msg_to_dict(cls(data=value))
        assert wire == {"data": value}
        back = conversion.dict_to_msg(cls, wire)
        assert back.data == value, cls


def test_time_and_duration_as_secs_nsecs() -> None:
    wire = conversion.msg_to_dict(std.Time(data=genpy.Time(5, 7)))
    assert wire == {"data": {"secs": 5, "nsecs": 7}}
    assert conversion.dict_to_msg(std.Duration, {"data": {"secs": -3, "nsecs": 9}}).data == genpy.Duration(-3, 9)
    # ROS 2 spelling is accepted as input too
    assert conversion.dict_to_msg(std.Time, {"data": {"sec": 1, "nanosec": 2}}).data == genpy.Time(1, 2)


def test_nan_and_inf_become_null_in_json_but_stay_exact_in_cbor() -> None:
    msg = std.Float64MultiArray(data=[1.0, float("nan"), float("inf"), -float("inf")])
    assert conversion.msg_to_dict(msg)["data"] == [1.0, None, None, None]
    scalar = conversion.msg_to_dict(std.Float32(data=float("nan")))
    assert scalar == {"data": None}
    encoding.encode_json({"m": conversion.msg_to_dict(msg)})  # valid JSON: no NaN token
    assert "NaN" not in encoding.encode_json({"m": conversion.msg_to_dict(msg)})
    tagged = conversion.msg_to_dict(msg, cbor=True)["data"]
    assert tagged.tag == 86
    values = struct.unpack("<4d", tagged.value)
    assert values[0] == 1.0 and math.isnan(values[1]) and values[2] == math.inf and values[3] == -math.inf
    # null comes back as NaN
    assert math.isnan(conversion.dict_to_msg(std.Float64, {"data": None}).data)


def test_byte_arrays_base64_in_json_raw_in_cbor_and_accept_lists() -> None:
    img = sensor.CompressedImage(format="jpeg", data=bytes(range(256)))
    wire = conversion.msg_to_dict(img)
    assert wire["data"] == base64.b64encode(bytes(range(256))).decode()
    assert conversion.msg_to_dict(img, cbor=True)["data"] == bytes(range(256))
    assert conversion.dict_to_msg(sensor.CompressedImage, wire).data == bytes(range(256))
    assert conversion.dict_to_msg(sensor.CompressedImage, {"data": [1, 2, 3]}).data == b"\x01\x02\x03"
    assert conversion.dict_to_msg(sensor.CompressedImage, {"data": b"\x09"}).data == b"\x09"
    with pytest.raises(ConversionError, match="data"):
        conversion.dict_to_msg(sensor.CompressedImage, {"data": [1, 300]})
    with pytest.raises(ConversionError, match="base64"):
        conversion.dict_to_msg(sensor.CompressedImage, {"data": "***"})


def test_fixed_and_variable_arrays_and_nested_messages() -> None:
    imu = sensor.Imu()
    imu.orientation_covariance = [float(i) for i in range(9)]
    wire = conversion.msg_to_dict(imu)
    assert wire["orientation_covariance"] == [float(i) for i in range(9)]
    assert wire["header"] == {"seq": 0, "stamp": {"secs": 0, "nsecs": 0}, "frame_id": ""}
    with pytest.raises(ConversionError, match=r"orientation_covariance.*expected 9"):
        conversion.dict_to_msg(sensor.Imu, {"orientation_covariance": [1.0]})
    poses = {"header": {"frame_id": "map", "stamp": {"secs": 1, "nsecs": 0}},
             "poses": [{"position": {"x": 1.0, "y": 2, "z": 3}, "orientation": {"w": 1.0}}]}
    pa = conversion.dict_to_msg(geo.PoseArray, poses)
    assert pa.poses[0].position.y == 2.0 and pa.poses[0].orientation.w == 1.0
    assert conversion.msg_to_dict(pa)["poses"][0]["position"] == {"x": 1.0, "y": 2.0, "z": 3.0}
    # int arrays in CBOR are typed arrays
    tag = conversion.msg_to_dict(std.Int32MultiArray(data=[1, -2]), cbor=True)["data"]
    assert tag.tag == 78 and struct.unpack("<2i", tag.value) == (1, -2)


def test_cbor_typed_arrays_are_accepted_as_input() -> None:
    msg = conversion.dict_to_msg(std.Float64MultiArray,
                                 {"data": cbor2.CBORTag(86, struct.pack("<3d", 1.0, 2.0, 3.0))})
    assert list(msg.data) == [1.0, 2.0, 3.0]


def test_header_filled_when_omitted() -> None:
    msg = conversion.dict_to_msg(geo.PoseStamped, {"pose": {}})
    assert msg.header.frame_id == "" and msg.header.seq == 0
    # rospy not initialised in this process part: stamp is filled with a Time, not left unset
    assert isinstance(msg.header.stamp, genpy.Time)
    only_frame = conversion.dict_to_msg(geo.PoseStamped, {"header": {"frame_id": "tool0"}})
    assert only_frame.header.frame_id == "tool0"


@pytest.mark.parametrize("cls,data,path", [
    (std.Int8, {"data": 128}, "data"),
    (std.UInt8, {"data": -1}, "data"),
    (std.Bool, {"data": "yes"}, "data"),
    (std.String, {"data": 5}, "data"),
    (std.Float64, {"data": "1.0"}, "data"),
    (std.Int32, {"data": True}, "data"),
    (geo.Pose, {"position": {"x": "a"}}, "position.x"),
    (geo.Pose, {"positon": {}}, "positon"),
    (geo.PoseArray, {"poses": [{}, {"position": []}]}, "poses[1].position"),
    (std.Time, {"data": {"secs": 1.5}}, "data"),
    (std.String, ["not", "a", "dict"], ""),
])
def test_mismatches_name_the_field(cls: type, data: object, path: str) -> None:
    with pytest.raises(ConversionError) as err:
        conversion.dict_to_msg(cls, data)
    assert err.value.path == path


def test_missing_fields_are_reported_and_defaulted() -> None:
    missing: list = []
    msg = conversion.dict_to_msg(geo.Point, {"x": 1}, missing=missing)
    assert (msg.x, msg.y, msg.z) == (1.0, 0.0, 0.0)
    assert missing == ["y", "z"]


def test_unknown_types_and_service_args() -> None:
    with pytest.raises(conversion.UnknownTypeError):
        conversion.get_message_class("no_pkg/Nothing")
    assert conversion.get_message_class("std_msgs/msg/String") is std.String  # ROS 2 spelling
    from std_srvs.srv import SetBool
    req = conversion.args_to_request(SetBool._request_class, [True])
    assert req.data is True
    assert conversion.args_to_request(SetBool._request_class, {"data": False}).data is False
    with pytest.raises(ConversionError):
        conversion.args_to_request(SetBool._request_class, [True, 1])


def test_png_and_fragment_encodings_invert() -> None:
    text = encoding.encode_json({"op": "publish", "topic": "/x", "msg": {"data": "y" * 1000}})
    assert encoding.png_decode(encoding.png_encode(text)) == text
    frames = encoding.fragment(text, "f1", 100)
    parts = [encoding.decode_frame(f) for f in frames]
    assert all(p["op"] == "fragment" and p["total"] == len(frames) for p in parts)
    assert "".join(p["data"] for p in parts) == text
