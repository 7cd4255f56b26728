"""The demo cell's module nodes (system_monitor, vision, vision_monitor) on a live ROS graph: one test body for ROS 1
and ROS 2 (scripts/test-all.sh runs this file under .venv-ros2 too). The test stands for a camera (a grey PNG as
sensor_msgs/CompressedImage) and reads what the nodes publish through our wiring, as the alarms and inspect nodes
would."""
from __future__ import annotations

import io
import threading
from typing import Any, Dict, Iterator, List

import pytest

from cell_nodes.ros_diagnostics import level_of
from conftest import wait_for
from nodes_helpers import Nodes, peer

CAMERA = "/monitor_test/camera/compressed"


def png(grey: int) -> bytes:
    from PIL import Image
    out = io.BytesIO()
    Image.new("L", (32, 24), grey).save(out, format="PNG")
    return out.getvalue()


class Latest:
    """The last message of each topic subscribed."""

    def __init__(self) -> None:
        self.values: Dict[str, Any] = {}
        self.lock = threading.Lock()
        self.subs: List[Any] = []

    def watch(self, topic: str, msg_cls: type, latched: bool = False) -> None:
        def keep(msg: Any, _sender: str) -> None:
            with self.lock:
                self.values[topic] = msg
        self.subs.append(peer().subscribe(topic, msg_cls, keep, queue_size=10, latched=latched))

    def get(self, topic: str) -> Any:
        with self.lock:
            return self.values.get(topic)

    def close(self) -> None:
        for sub in self.subs:
            sub.close()


@pytest.fixture(scope="module")
def monitors(ros_graph: str) -> Iterator[Nodes]:
    peer("monitor_test_client")
    nodes = Nodes()
    nodes.run("system_monitor", "system_monitor_node", "__name:=system_monitor_test")
    nodes.run("vision_monitor", "vision_monitor_node", "__name:=vision_monitor_test")
    nodes.run("vision", "vision_node", f"_topic:={CAMERA}", "_period:=0.2", "__name:=vision_test")
    try:
        wait_for(nodes.alive, 2, what="the nodes start")
        yield nodes
    finally:
        nodes.stop()
        nodes.check()


def test_load_and_brightness_verdicts_with_their_diagnostics(monitors: Nodes) -> None:
    from diagnostic_msgs.msg import DiagnosticArray
    from sensor_msgs.msg import CompressedImage
    from std_msgs.msg import Float32, String
    latest = Latest()
    statuses: Dict[str, Any] = {}

    def on_diagnostics(msg: Any, _sender: str) -> None:
        for status in msg.status:
            statuses[status.name] = status

    diag = peer().subscribe("/diagnostics", DiagnosticArray, on_diagnostics, queue_size=50)
    latest.watch("/cell/diagnostics/load", Float32)
    latest.watch("/cell/vision/status", String, latched=True)
    latest.watch("/cell/vision/brightness", Float32)
    camera = peer().publisher(CAMERA, CompressedImage, queue_size=1)
    try:
        wait_for(lambda: latest.get("/cell/diagnostics/load") is not None, 10, what="the load")
        assert 0.0 <= latest.get("/cell/diagnostics/load").data < 100
        wait_for(lambda: "system_monitor: CPU load" in statuses, 10, what="the load's diagnostic")
        # no camera yet: no image
        wait_for(lambda: getattr(latest.get("/cell/vision/status"), "data", "") == "no image", 10, what="no image")
        wait_for(lambda: "vision: camera brightness" in statuses, 10, what="the vision diagnostic")
        assert level_of(statuses["vision: camera brightness"]) == 1  # WARN

        def frames(grey: int, verdict: str) -> bool:
            camera.publish(CompressedImage(format="png", data=png(grey)))
            return getattr(latest.get("/cell/vision/status"), "data", "") == verdict

        wait_for(lambda: frames(250, "overexposed"), 15, what="an overexposed verdict")
        assert latest.get("/cell/vision/brightness").data > 0.9
        wait_for(lambda: frames(128, "ok"), 15, what="an ok verdict")
        wait_for(lambda: level_of(statuses["vision: camera brightness"]) == 0, 10, what="the vision diagnostic OK")
        wait_for(lambda: frames(5, "dark"), 15, what="a dark verdict")
    finally:
        diag.close()
        camera.close()
        latest.close()
