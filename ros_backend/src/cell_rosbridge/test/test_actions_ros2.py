"""The action ops of rosbridge_suite's ROS 2 protocol against a real rclpy action server (ROS 2 only: ROS 1's
protocol has no action ops; test_generations.py shows what a ROS 1 server answers)."""
from __future__ import annotations

import os
import signal
import subprocess
import sys
from pathlib import Path
from typing import Any, Dict, Iterator, List

import pytest

from rb_helpers import BridgeProcess
from rb_wsclient import WSClient

ACTION = "/test_arm/follow_joint_trajectory"
TYPE = "control_msgs/action/FollowJointTrajectory"


@pytest.fixture(scope="module")
def server(ros_graph: str) -> Iterator[BridgeProcess]:
    b = BridgeProcess(name="rosbridge_actions")
    yield b
    assert b.stop() == 0, b.log()


@pytest.fixture(scope="module")
def action_server(ros_graph: str) -> Iterator[subprocess.Popen]:
    proc = subprocess.Popen([sys.executable, str(Path(__file__).with_name("action_server_ros2.py"))],
                            stdout=subprocess.PIPE, text=True, start_new_session=True, env=dict(os.environ))
    assert proc.stdout is not None and proc.stdout.readline().strip() == "ready"
    yield proc
    proc.send_signal(signal.SIGINT)
    proc.wait(10)


def goal(joints: List[str], points: int) -> Dict[str, Any]:
    return {"trajectory": {"joint_names": joints, "points": [
        {"positions": [0.1 * i] * len(joints), "time_from_start": {"sec": i, "nanosec": 0}}
        for i in range(1, points + 1)]}}


def messages_until_result(ws: WSClient, gid: str, feedback: int = 0) -> List[Dict[str, Any]]:
    """The goal's messages until its result and `feedback` feedbacks came (feedback travels on a topic, the result
    as a service answer: the last feedback may come after the result), the result last."""
    seen: List[Dict[str, Any]] = []

    def done(m: Any) -> bool:
        if isinstance(m, dict) and m.get("id") == gid:
            seen.append(m)
        ops = [x.get("op") for x in seen]
        return "action_result" in ops and ops.count("action_feedback") >= feedback

    ws.recv_until(done, 15)
    return sorted(seen, key=lambda m: m.get("op") == "action_result")


def test_a_goal_gets_its_feedback_and_result(server: BridgeProcess, action_server: subprocess.Popen) -> None:
    ws = WSClient(server.port, timeout=15)
    try:
        # The server keeps one action client per action: its feedback reader, once matched, hears every feedback
        # of later goals. (The first goal to an action may start before DDS matched the new reader, and lose the
        # feedback sent at once, as with any new ROS 2 action client.)
        ws.send_json({"op": "send_action_goal", "id": "g0", "action": ACTION, "action_type": TYPE,
                      "args": goal(["j1"], 1)})
        assert messages_until_result(ws, "g0")[-1]["status"] == 4
        ws.send_json({"op": "send_action_goal", "id": "g1", "action": ACTION, "action_type": TYPE,
                      "args": goal(["j1", "j2"], 3), "feedback": True})
        seen = messages_until_result(ws, "g1", feedback=3)
        feedback = [m for m in seen if m["op"] == "action_feedback"]
        assert [m["values"]["desired"]["positions"] for m in feedback] == [[0.1, 0.1], [0.2, 0.2],
                                                                          [0.30000000000000004] * 2]
        result = seen[-1]
        assert result["action"] == ACTION and result["result"] is True and result["status"] == 4  # SUCCEEDED
        assert result["values"] == {"error_code": 0, "error_string": "3 points"}
    finally:
        ws.close()


def test_a_rejected_goal_and_a_bad_goal_fail_clearly(server: BridgeProcess, action_server: subprocess.Popen) -> None:
    ws = WSClient(server.port, timeout=15)
    try:
        ws.send_json({"op": "send_action_goal", "id": "r1", "action": ACTION, "action_type": TYPE, "args": goal([], 1)})
        out = messages_until_result(ws, "r1")[-1]
        assert out["result"] is False and "rejected" in out["values"]
        ws.send_json({"op": "send_action_goal", "id": "b1", "action": ACTION, "action_type": TYPE,
                      "args": {"trajectory": {"joint_names": "j1"}}})
        out = messages_until_result(ws, "b1")[-1]
        assert out["result"] is False and "trajectory.joint_names" in out["values"]
        ws.send_json({"op": "send_action_goal", "id": "t1", "action": ACTION, "action_type": "no_pkg/action/Nope"})
        out = messages_until_result(ws, "t1")[-1]
        assert out["result"] is False and "no_pkg" in out["values"]
    finally:
        ws.close()


def test_cancel_ends_a_running_goal_as_canceled(server: BridgeProcess, action_server: subprocess.Popen) -> None:
    ws = WSClient(server.port, timeout=15)
    try:
        ws.send_json({"op": "send_action_goal", "id": "c1", "action": ACTION, "action_type": TYPE,
                      "args": goal(["hold"], 1), "feedback": True})
        ws.recv_until(lambda m: isinstance(m, dict) and m.get("op") == "action_feedback" and m.get("id") == "c1", 15)
        ws.send_json({"op": "cancel_action_goal", "id": "c1", "action": ACTION})
        out = messages_until_result(ws, "c1")[-1]
        assert out["result"] is True and out["status"] == 5 and out["values"]["error_string"] == "canceled"
        ws.send_json({"op": "cancel_action_goal", "id": "c1", "action": ACTION})  # over: nothing to cancel
        status = ws.recv_until(lambda m: isinstance(m, dict) and m.get("op") == "status", 10)
        assert status["level"] == "error" and "no goal" in status["msg"]
    finally:
        ws.close()


def test_a_client_that_leaves_cancels_its_goal(server: BridgeProcess, action_server: subprocess.Popen) -> None:
    ws = WSClient(server.port, timeout=15)
    ws.send_json({"op": "send_action_goal", "id": "l1", "action": ACTION, "action_type": TYPE,
                  "args": goal(["hold"], 1), "feedback": True})
    ws.recv_until(lambda m: isinstance(m, dict) and m.get("op") == "action_feedback", 15)
    ws.close()
    watcher = WSClient(server.port, timeout=15)  # the held goal ended: the server takes the next one
    try:
        watcher.send_json({"op": "send_action_goal", "id": "after", "action": ACTION, "action_type": TYPE,
                           "args": goal(["j1"], 1)})
        assert messages_until_result(watcher, "after")[-1]["status"] == 4
    finally:
        watcher.close()


def test_roslibjs_talks_to_the_ros2_server(server: BridgeProcess, action_server: subprocess.Popen) -> None:
    """roslib 2.x, the app's own client library (its Action class speaks the action ops), under Node."""
    from rb_helpers import ROOT
    proc = subprocess.run(["node", str(Path(__file__).with_name("roslib_ros2.mjs")), str(server.port), server.name],
                          cwd=ROOT, capture_output=True, text=True, timeout=60)
    out = proc.stdout + proc.stderr
    assert proc.returncode == 0 and "ALL OK" in out and out.count("ok ") >= 4, out
