"""The browser client library (roslib 2.x, under Node) against our server."""
from __future__ import annotations

import math
import pathlib
import subprocess

import rospy
import std_msgs.msg as std

from rb_helpers import ROOT, BridgeProcess

SCRIPT = pathlib.Path(__file__).with_name("roslib_conformance.mjs")


def test_roslib_conformance(ros_node: str, bridge: BridgeProcess) -> None:
    from cell_msgs.msg import OperationMode
    mode = rospy.Publisher("/rc_mode", OperationMode, queue_size=1, latch=True)
    mode.publish(OperationMode(mode="running", source="test", stamp=rospy.Time(5, 0)))
    arr = rospy.Publisher("/rc_array", std.Float64MultiArray, queue_size=1, latch=True)
    arr.publish(std.Float64MultiArray(data=[1.5, math.nan, -2.0]))
    assert (ROOT / "node_modules" / "roslib").is_dir()
    proc = subprocess.run(["node", str(SCRIPT), str(bridge.port)], cwd=ROOT, capture_output=True, text=True,
                          timeout=60)
    out = proc.stdout + proc.stderr
    assert proc.returncode == 0, out
    assert "ALL OK" in out and "FAIL" not in out, out
    assert out.count("\nok ") + out.startswith("ok ") >= 13, out
    mode.unregister()
    arr.unregister()
