"""A ROS 2 stack's discovery stays on this machine: with the stack's environment (scripts/ros2-env.sh:
localhost-only discovery, a domain of its own) its nodes find each other over loopback and send no packet on any
other interface.

The nodes run in a network namespace of the test's own whose only other interface is one end of a veth pair: every
packet they send there is counted on the other end, outside. The same run with discovery over the subnet (what a
robot PC on its robot network sets) does send there: the count can fail.
"""
from __future__ import annotations

import os
import pathlib
import subprocess
import sys
import uuid
from typing import Dict, Iterator

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[3]
NODE = ROOT / "ros_backend" / "src" / "cell_nodes" / "scripts" / "operation_mode_node"
CELL = ROOT / "config" / "demo-cell.yaml"
# Asks the node's get-mode service through our wiring, as the stack's other nodes and the bridge do.
ASK = """
import sys
from cell_msgs.srv import GetMode
from cell_nodes import wiring
ros = wiring.connect("discovery_probe", disable_signals=True)
client = ros.client("/cell/get_mode", GetMode)
print(client(timeout=20).mode, flush=True)
ros.shutdown()
"""


def sh(*cmd: str) -> None:
    subprocess.run(cmd, check=True, capture_output=True, timeout=20)


@pytest.fixture
def netns() -> Iterator[Dict[str, str]]:
    tag = uuid.uuid4().hex[:6]
    ns, outside, inside = f"rosdisc{tag}", f"vo{tag}", f"vi{tag}"
    sh("ip", "netns", "add", ns)
    try:
        sh("ip", "link", "add", outside, "type", "veth", "peer", "name", inside)
        sh("ip", "link", "set", inside, "netns", ns)
        for side, cmd in ((outside, ()), (inside, ("ip", "netns", "exec", ns))):
            sh(*cmd, "sysctl", "-q", "-w", f"net.ipv6.conf.{side}.disable_ipv6=1")  # no router solicitations
        sh("ip", "addr", "add", "10.213.77.1/24", "dev", outside)
        sh("ip", "link", "set", outside, "up")
        sh("ip", "netns", "exec", ns, "ip", "addr", "add", "10.213.77.2/24", "dev", inside)
        sh("ip", "netns", "exec", ns, "ip", "link", "set", inside, "up")
        sh("ip", "netns", "exec", ns, "ip", "link", "set", "lo", "up")
        yield {"ns": ns, "outside": outside}
    finally:
        subprocess.run(["ip", "link", "del", outside], capture_output=True)
        subprocess.run(["ip", "netns", "del", ns], capture_output=True)


def received(iface: str) -> int:
    return int(pathlib.Path(f"/sys/class/net/{iface}/statistics/rx_packets").read_text())


def run_stack(ns: str, discovery_range: str) -> str:
    """The operation mode node and a client of it in the namespace; the mode the client got."""
    env = dict(os.environ, ROS_AUTOMATIC_DISCOVERY_RANGE=discovery_range, ROS_DOMAIN_ID="42")
    node = subprocess.Popen(["ip", "netns", "exec", ns, sys.executable, str(NODE), "--ros-args", "-p",
                             f"cell_config:={CELL}"], env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    try:
        probe = subprocess.run(["ip", "netns", "exec", ns, sys.executable, "-c", ASK], env=env, capture_output=True,
                               text=True, timeout=60)
        assert probe.returncode == 0, probe.stderr
        return probe.stdout.strip()
    finally:
        node.terminate()
        node.wait(10)


def test_localhost_discovery_sends_nothing_off_loopback(netns: Dict[str, str]) -> None:
    before = received(netns["outside"])
    assert run_stack(netns["ns"], "LOCALHOST") == "idle"  # the two nodes found each other
    assert received(netns["outside"]) - before == 0


def test_subnet_discovery_does_send_there(netns: Dict[str, str]) -> None:
    before = received(netns["outside"])
    assert run_stack(netns["ns"], "SUBNET") == "idle"
    assert received(netns["outside"]) - before > 0
