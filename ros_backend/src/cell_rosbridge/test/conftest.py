"""Fixtures for the rosbridge suite: a test ROS node, bridge processes, rosapi, clients."""
from __future__ import annotations

import os
import subprocess
import sys
import tempfile
from typing import Callable, Iterator, List

import pytest

from rb_helpers import ROS_VERSION, ROSAPI, BridgeProcess, wait_for

# What exists on ROS 2 only (the action ops): scripts/test-all.sh runs those files under .venv-ros2.
collect_ignore_glob = ["*_ros2.py"] if ROS_VERSION == 1 else []


@pytest.fixture(scope="session")
def ros_node(roscore: str) -> str:
    """This test process as a ROS node (helper publishers, subscribers, service callers)."""
    import rospy
    # One ROS node per process: another suite in the same pytest session may have made it already.
    if not rospy.core.is_initialized():
        rospy.init_node("rosbridge_tests", anonymous=True, disable_signals=True)
    return rospy.get_name()


@pytest.fixture(scope="session")
def rosapi(roscore: str) -> Iterator[subprocess.Popen]:
    import rosgraph
    # Its stderr is kept, with every ResourceWarning shown: a socket left to the garbage collector is a leak there.
    stderr = tempfile.NamedTemporaryFile(prefix="rosapi-stderr-", suffix=".log", delete=False)
    proc = subprocess.Popen([sys.executable, str(ROSAPI)], stdout=subprocess.DEVNULL, stderr=stderr,
                            env=dict(os.environ, PYTHONWARNINGS="always::ResourceWarning"), start_new_session=True)
    proc.stderr_path = stderr.name  # type: ignore[attr-defined]
    master = rosgraph.Master("/rb_test")
    wait_for(lambda: any(s == "/rosapi/topics_and_raw_types" for s, _ in master.getSystemState()[2]),
             20, what="rosapi services")
    yield proc
    proc.terminate()
    proc.wait(10)


@pytest.fixture(scope="session")
def bridge(roscore: str, rosapi: subprocess.Popen) -> Iterator[BridgeProcess]:
    """The shared server most tests talk to."""
    b = BridgeProcess()
    yield b
    assert b.stop() == 0, b.log()


@pytest.fixture
def make_bridge(roscore: str) -> Iterator[Callable[..., BridgeProcess]]:
    """Private servers for tests that need special limits or kill/restart them."""
    made: List[BridgeProcess] = []

    def make(**kwargs: object) -> BridgeProcess:
        b = BridgeProcess(**kwargs)  # type: ignore[arg-type]
        made.append(b)
        return b

    yield make
    for b in made:
        b.stop()


@pytest.fixture
def ros_client(bridge: BridgeProcess) -> Iterator[Callable[..., object]]:
    """roslibpy connections to the shared server, closed after the test."""
    import roslibpy
    made: list = []

    def connect(port: int = 0) -> roslibpy.Ros:
        ros = roslibpy.Ros("127.0.0.1", port or bridge.port)
        ros.run(timeout=10)
        made.append(ros)
        return ros

    yield connect
    for ros in made:
        if ros.is_connected:
            ros.close()
