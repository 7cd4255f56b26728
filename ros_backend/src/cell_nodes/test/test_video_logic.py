"""The video node's logic without ROS: raw frames to pictures, sizes in shared steps clamped to the camera, one
encoding per frame size however many viewers, the camera subscribed only while watched, and errors reported."""
from __future__ import annotations

import io
from types import SimpleNamespace

import numpy as np
import pytest
from PIL import Image

from cell_nodes.diagnostics import ERROR, OK, WARN
from cell_nodes.video.images import FrameError, Size, frame_size, picture, wanted
from cell_nodes.video.server import LINGER_S, NO_FRAME_S, OUTPUT_IDLE_S, RawStream, VideoServer, raw_streams


def frame(w=64, h=48, encoding="rgb8", step=None, data=None, value=(200, 100, 50), bigendian=0):
    bpp = {"rgb8": 3, "bgr8": 3, "mono8": 1, "16UC1": 2, "mono16": 2, "yuv422": 2}[encoding]
    if data is None:
        px = np.zeros((h, w, bpp), np.uint8)
        px[:] = value[:bpp]
        data = px.tobytes()
    return SimpleNamespace(encoding=encoding, width=w, height=h, step=step if step is not None else w * bpp,
                           data=data, is_bigendian=bigendian, header="hdr")


def test_rgb_bgr_and_mono_frames_become_pictures_with_the_right_colours():
    assert picture(**_fields(frame(encoding="rgb8"))).getpixel((3, 3)) == (200, 100, 50)
    assert picture(**_fields(frame(encoding="bgr8"))).getpixel((3, 3)) == (50, 100, 200)
    assert picture(**_fields(frame(encoding="mono8", value=(77,)))).getpixel((3, 3)) == 77


def test_padded_rows_are_cut_to_the_width():
    w, h, step = 10, 4, 40   # 30 bytes of pixels, 10 of padding per row
    rows = np.zeros((h, step), np.uint8)
    rows[:, :30] = 9
    rows[:, 30:] = 255
    img = picture("rgb8", w, h, step, rows.tobytes())
    assert img.size == (10, 4) and set(np.asarray(img).ravel()) == {9}


def test_16_bit_depth_is_grey_near_dark_far_light_and_no_reading_black():
    v = np.array([[0, 1000, 2000, 3000]], dtype="<u2")
    img = picture("16UC1", 4, 1, 8, v.tobytes())
    g = list(np.asarray(img)[0])
    assert g[0] == 0 and 0 < g[1] < g[2] < g[3] == 255
    big = picture("mono16", 4, 1, 8, v.astype(">u2").tobytes(), bigendian=True)
    assert list(np.asarray(big)[0]) == g


def test_an_unsupported_encoding_or_a_short_frame_says_which():
    with pytest.raises(FrameError, match="unsupported encoding yuv422"):
        picture(**_fields(frame(encoding="yuv422")))
    with pytest.raises(FrameError, match="does not match its header"):
        picture("rgb8", 64, 48, 192, b"\0" * 100)
    with pytest.raises(FrameError, match="does not match its header"):
        picture("rgb8", 64, 48, 10, b"\0" * 64 * 48 * 3)   # rows shorter than the width
    with pytest.raises(FrameError, match="empty"):
        picture("rgb8", 0, 48, 0, b"")


def test_sizes_are_asked_in_shared_steps_and_never_larger_than_the_camera():
    assert wanted(1170, 70) == Size(1280, 70)          # a phone: 390 css px at DPR 3
    assert wanted(1100, 72) == Size(1120, 70)
    assert wanted(1, 1) == Size(160, 10)
    assert wanted(0, 0) == Size(0, 70)                 # the camera's own width, the default quality
    assert wanted(100000, 400) == Size(7680, 100)
    assert frame_size(Size(7680, 70), (1280, 720)) == (1280, 720)
    assert frame_size(Size(640, 70), (1280, 720)) == (640, 360)
    assert frame_size(Size(0, 70), (640, 480)) == (640, 480)


class Pub:
    def __init__(self, topic):
        self.topic, self.connections, self.sent, self.gone = topic, 0, [], False

    def subscriber_count(self):
        return self.connections

    def publish(self, msg):
        self.sent.append(msg)

    def close(self):
        self.gone = True


class Rig:
    def __init__(self, streams=(RawStream("Arm", "/cam/raw"),)):
        self.now = 100.0
        self.pubs: dict[str, Pub] = {}
        self.subs: list[list] = []   # [topic, callback, unregistered]
        self.encodes = 0

        def advertise(topic):
            self.pubs[topic] = Pub(topic)
            return self.pubs[topic]

        def subscribe(topic, cb):
            entry = [topic, cb, False]
            self.subs.append(entry)
            return SimpleNamespace(close=lambda: entry.__setitem__(2, True))

        def to_msg(src, data):
            self.encodes += 1
            return SimpleNamespace(header=src.header, data=data)

        self.server = VideoServer(list(streams), advertise, subscribe, to_msg, clock=lambda: self.now)

    def live_subs(self):
        return [s for s in self.subs if not s[2]]


def _size(jpeg_bytes):
    return Image.open(io.BytesIO(jpeg_bytes)).size


def test_viewers_of_one_size_share_one_encoding_per_frame_and_each_size_gets_its_own():
    rig = Rig()
    a = rig.server.request("/cam/raw", 1170, 70)
    b = rig.server.request("/cam/raw", 1200, 70)
    c = rig.server.request("/cam/raw", 300, 70)
    assert a.ok and a.topic == b.topic != c.topic
    rig.pubs[a.topic].connections = 3
    rig.pubs[c.topic].connections = 1
    assert rig.server.tick()[0].level == OK
    [(topic, cb, _)] = rig.live_subs()
    cb(frame(w=1280, h=720))
    assert rig.encodes == 2
    assert _size(rig.pubs[a.topic].sent[0].data) == (1280, 720)
    assert _size(rig.pubs[c.topic].sent[0].data) == (320, 180)
    assert rig.pubs[a.topic].sent[0].header == "hdr"    # the camera's stamp: the viewer's age is the camera's
    # the camera's size is known now: an absurd width gets the camera's own, on the output that has it
    big = rig.server.request("/cam/raw", 100000, 70)
    assert (big.width, big.height) == (1280, 720) and big.topic.endswith("/full_q70")
    zero = rig.server.request("/cam/raw", 0, 0)
    assert zero.topic == big.topic


def test_the_camera_is_subscribed_only_while_watched():
    rig = Rig()
    a = rig.server.request("/cam/raw", 640, 70)
    rig.server.tick()
    assert rig.live_subs() == []                        # asked, but nobody subscribed the output yet
    rig.pubs[a.topic].connections = 1
    rig.server.tick()
    assert len(rig.live_subs()) == 1
    rig.pubs[a.topic].connections = 0
    rig.server.tick()
    rig.now += LINGER_S / 2
    rig.server.tick()
    assert len(rig.live_subs()) == 1                    # a viewer switching sizes does not make it churn
    rig.now += LINGER_S
    rig.server.tick()
    assert rig.live_subs() == []
    rig.now += OUTPUT_IDLE_S + 1
    rig.server.tick()
    assert rig.pubs[a.topic].gone                       # unadvertised after long without a viewer


def test_a_bad_frame_is_reported_and_the_next_good_one_clears_it_and_other_streams_go_on():
    rig = Rig((RawStream("Arm", "/cam/raw"), RawStream("Depth", "/cam/depth")))
    a = rig.server.request("/cam/raw", 320, 70)
    d = rig.server.request("/cam/depth", 320, 70)
    rig.pubs[a.topic].connections = rig.pubs[d.topic].connections = 1
    rig.server.tick()
    subs = {t: cb for t, cb, _ in rig.live_subs()}
    subs["/cam/raw"](frame(encoding="yuv422"))
    subs["/cam/depth"](frame(encoding="16UC1", value=(10, 1)))
    arm, depth = rig.server.tick()
    assert arm.level == ERROR and "unsupported encoding yuv422" in arm.message and arm.hardware_id == "/cam/raw"
    assert depth.level == OK and len(rig.pubs[d.topic].sent) == 1
    assert "unsupported encoding" in rig.server.request("/cam/raw", 320, 70).message
    subs["/cam/raw"](frame())
    assert rig.server.tick()[0].level == OK and len(rig.pubs[a.topic].sent) == 1


def test_a_watched_camera_that_sends_nothing_is_reported():
    rig = Rig()
    a = rig.server.request("/cam/raw", 320, 70)
    rig.pubs[a.topic].connections = 1
    rig.server.tick()
    rig.now += NO_FRAME_S + 1
    [s] = rig.server.tick()
    assert s.level == WARN and "no frame from /cam/raw" in s.message


def test_only_the_cell_files_raw_streams_are_served():
    rig = Rig()
    assert not rig.server.request("/other", 320, 70).ok
    cell = {"video": {"streams": [{"name": "A", "topic": "/a"}, {"name": "B", "topic": "/b", "type": "raw"}]}}
    assert raw_streams(cell) == [RawStream("B", "/b")]


def _fields(f):
    return dict(encoding=f.encoding, width=f.width, height=f.height, step=f.step, data=f.data,
                bigendian=bool(f.is_bigendian))
