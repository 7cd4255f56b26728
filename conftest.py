"""Shared pytest fixtures: a live, isolated roscore for the Python suites."""
from __future__ import annotations

import os
import signal
import socket
import subprocess
import sys
import tempfile
import time
from typing import Iterator

import pytest


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def wait_for(predicate, timeout: float = 10.0, interval: float = 0.05, what: str = "condition") -> None:
    """Poll `predicate` until it returns truthy; fail the test after `timeout` seconds."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if predicate():
            return
        time.sleep(interval)
    raise AssertionError(f"timed out after {timeout}s waiting for {what}")


@pytest.fixture(scope="session")
def roscore() -> Iterator[str]:
    """Start a roscore on a free port; export ROS_MASTER_URI for the session; yield the URI."""
    import rosgraph

    port = free_port()
    uri = f"http://127.0.0.1:{port}"
    home = tempfile.mkdtemp(prefix="roshome-")
    env = dict(os.environ, ROS_MASTER_URI=uri, ROS_HOSTNAME="127.0.0.1", ROS_HOME=home, ROS_LOG_DIR=home)
    proc = subprocess.Popen(["roscore", "-p", str(port)], env=env, stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL, start_new_session=True)
    os.environ.update(ROS_MASTER_URI=uri, ROS_HOSTNAME="127.0.0.1", ROS_HOME=home, ROS_LOG_DIR=home)
    try:
        wait_for(lambda: rosgraph.is_master_online(uri), 15, what="roscore")
        yield uri
    finally:
        proc.send_signal(signal.SIGTERM)
        try:
            proc.wait(10)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)


ROS_VERSION = 2 if os.environ.get("ROS_VERSION") == "2" else 1


@pytest.fixture(scope="session")
def ros_graph(request: pytest.FixtureRequest) -> str:
    """A ROS graph of this session's own, for tests written once for both generations: ROS 1, a live roscore
    (its URI); ROS 2, a domain of its own with localhost-only discovery (no master: the domain's id)."""
    if ROS_VERSION == 1:
        return request.getfixturevalue("roscore")
    domain = str(100 + os.getpid() % 100)  # 100-199: beside the stacks' own domains (scripts/stack.js)
    home = tempfile.mkdtemp(prefix="ros2home-")
    os.environ.update(ROS_DOMAIN_ID=domain, ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST", ROS_HOME=home,
                      ROS_LOG_DIR=home)
    return domain


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item, call):
    """A failing test's report shows the end of the log of each ROS node running then (the node tests'
    nodes_helpers: the nodes of a module-scoped fixture outlive the test, their logs end up removed)."""
    outcome = yield
    report = outcome.get_result()
    helpers = sys.modules.get("nodes_helpers")
    if report.failed and helpers is not None:
        for label, text in helpers.running_logs():
            report.sections.append((f"log of the node {label} ({report.when})", text))
