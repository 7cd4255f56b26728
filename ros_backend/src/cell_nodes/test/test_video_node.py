"""The video node on a live ROS graph, one body for ROS 1 and ROS 2 (scripts/test-all.sh runs it under .venv-ros2
too): `video_node` with a cell file of two raw streams, this test standing for the camera drivers (1280x720 rgb8, and
one sending an encoding the node cannot show) through the nodes' wiring. A viewer's request names a JPEG topic whose
frames have the width asked (an absurd width gets the camera's own); the node subscribes the camera only while that
topic has a subscriber (the graph says so); the bad camera is reported on /cell/video/status while the good one keeps
being served."""
from __future__ import annotations

import io
import threading
import time
from pathlib import Path
from typing import Any, Iterator

import numpy as np
import pytest
import yaml
from PIL import Image as PILImage

from cell_nodes.ros_diagnostics import level_of
from conftest import wait_for
from nodes_helpers import Nodes, peer

ROOT = Path(__file__).resolve().parents[4]
GOOD, BAD = "/video_test/arm/image_raw", "/video_test/odd/image_raw"


@pytest.fixture(scope="module")
def video(ros_graph: str, tmp_path_factory: Any) -> Iterator[None]:
    doc = yaml.safe_load((ROOT / "config" / "demo-cell.yaml").read_text())
    doc["video"] = {"streams": [{"name": "Arm", "topic": GOOD, "type": "raw"},
                                {"name": "Odd", "topic": BAD, "type": "raw"},
                                {"name": "Jpeg", "topic": "/video_test/jpeg/image/compressed"}]}
    path = tmp_path_factory.mktemp("video") / "cell.yaml"
    path.write_text(yaml.safe_dump(doc))
    nodes = Nodes()
    node = nodes.run("video", "video_node", f"_cell_config:={path}", "__name:=video_test")
    cameras = Cameras()
    try:
        nodes.wait_ready("/cell/video/request", what="the video node's request service")
        yield
    finally:
        cameras.stop()
        nodes.stop()
        print(f"\nvideo log:\n{node.tail()}")
        nodes.check()


class Cameras:
    """Two camera drivers at 20 Hz: GOOD sends 1280x720 rgb8, BAD yuv422."""

    def __init__(self) -> None:
        from sensor_msgs.msg import Image
        self.pubs = {GOOD: peer().publisher(GOOD, Image, queue_size=1), BAD: peer().publisher(BAD, Image, queue_size=1)}
        px = np.zeros((720, 1280, 3), np.uint8)
        px[:, :640] = (255, 0, 0)
        self.good = Image(width=1280, height=720, encoding="rgb8", step=1280 * 3, data=px.tobytes())
        self.bad = Image(width=64, height=48, encoding="yuv422", step=128, data=bytes(128 * 48))
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._thread.start()

    def _run(self) -> None:
        while not self._stop.wait(0.05):
            self.good.header.stamp = self.bad.header.stamp = peer().stamp(time.time())
            self.pubs[GOOD].publish(self.good)
            self.pubs[BAD].publish(self.bad)

    def stop(self) -> None:
        self._stop.set()
        self._thread.join(2)
        for pub in self.pubs.values():
            pub.close()


def request(topic: str, width: int, quality: int = 70) -> Any:
    from cell_msgs.srv import VideoRequest
    return peer().client("/cell/video/request", VideoRequest)(topic=topic, width=width, quality=quality)


def frames(topic: str, n: int = 3) -> list[tuple[int, int]]:
    """The sizes of the next n JPEG frames on an output topic, read as a viewer would."""
    from sensor_msgs.msg import CompressedImage
    got: list[tuple[int, int]] = []
    sub = peer().subscribe(topic, CompressedImage,
                           lambda m, _s: got.append(PILImage.open(io.BytesIO(bytes(m.data))).size), newest_only=True)
    try:
        wait_for(lambda: len(got) >= n, 20, what=f"{n} frames on {topic}")
    finally:
        sub.close()
    return got[:n]


def test_a_viewer_gets_frames_of_the_width_it_asked_and_the_camera_is_read_only_while_watched(video: None) -> None:
    r = request(GOOD, 390 * 3)
    assert r.ok and r.topic.startswith("/cell/video/") and r.quality == 70
    assert peer().subscribers(GOOD) == []              # asked, not yet watched
    assert set(frames(r.topic)) == {(1280, 720)}       # 1170 px rounds up to 1280, the camera's own
    small = request(GOOD, 300)
    assert (small.width, small.height) == (320, 180)   # the camera's size is known now
    assert set(frames(small.topic)) == {(320, 180)}
    assert "/video_test" in peer().subscribers(GOOD)
    wait_for(lambda: peer().subscribers(GOOD) == [], 10, what="the node leaving the camera after its last viewer")
    huge = request(GOOD, 100000)
    assert (huge.width, huge.height) == (1280, 720)


def test_a_camera_sending_what_cannot_be_shown_is_reported_and_the_other_keeps_being_served(video: None) -> None:
    from diagnostic_msgs.msg import DiagnosticArray
    from sensor_msgs.msg import CompressedImage
    bad = request(BAD, 320)
    good = request(GOOD, 640)
    holder = peer().subscribe(bad.topic, CompressedImage, lambda m, _s: None)   # a viewer of the bad camera
    try:
        def bad_status() -> Any:
            m = peer().wait_for_message("/cell/video/status", DiagnosticArray, timeout=5)
            return next((s for s in m.status if s.hardware_id == BAD and level_of(s) == 2), None) if m else None
        wait_for(bad_status, 15, what="the bad camera's error on /cell/video/status")
        assert "unsupported encoding yuv422" in bad_status().message
        assert "unsupported encoding yuv422" in request(BAD, 320).message
        assert set(frames(good.topic)) == {(640, 360)}
    finally:
        holder.close()


def test_a_topic_that_is_not_a_raw_stream_is_refused(video: None) -> None:
    r = request("/video_test/jpeg/image/compressed", 640)
    assert not r.ok and "not a raw camera stream" in r.message
