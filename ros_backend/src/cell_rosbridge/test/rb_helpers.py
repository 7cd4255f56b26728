"""Shared test helpers (distinct module name: other suites in the session have their own helpers)."""
from __future__ import annotations

import importlib.util
import os
import pathlib
import signal
import socket
import subprocess
import sys
from typing import Callable, Dict, List, Optional

ROS_VERSION = 2 if os.environ.get("ROS_VERSION") == "2" else 1

ROOT = pathlib.Path(__file__).resolve().parents[4]
PKG = pathlib.Path(__file__).resolve().parents[1]
SERVER = PKG / "scripts" / "rosbridge_server"
ROSAPI = PKG.parent / "rosapi" / "scripts" / "rosapi_node"

_spec = importlib.util.spec_from_file_location("_root_conftest_for_rosbridge", ROOT / "conftest.py")
_root = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(_root)  # type: ignore[union-attr]
wait_for: Callable[..., None] = _root.wait_for  # the project's poll-until helper
free_port: Callable[[], int] = _root.free_port


def port_open(port: int) -> bool:
    with socket.socket() as s:
        s.settimeout(0.2)
        return s.connect_ex(("127.0.0.1", port)) == 0


class BridgeProcess:
    """A rosbridge_server node in its own process (rospy allows one node per process)."""

    def __init__(self, port: Optional[int] = None, params: Optional[Dict[str, object]] = None,
                 name: Optional[str] = None, env: Optional[Dict[str, str]] = None) -> None:
        self.port = port or free_port()
        self.name = name or f"rosbridge_{self.port}"
        args = [sys.executable, str(SERVER)]
        if ROS_VERSION == 2:  # node parameters
            args += ["--ros-args", "-r", f"__node:={self.name}", "-p", f"port:={self.port}"]
            for k, v in (params or {}).items():
                args += ["-p", f"{k}:={v}"]
        else:  # the ROS 1 node's private parameters
            args += [f"__name:={self.name}", f"_port:={self.port}"]
            args += [f"_{k}:={v}" for k, v in (params or {}).items()]
        self.log_path = pathlib.Path(os.environ.get("ROS_LOG_DIR", "/tmp")) / f"{self.name}.out"
        self._log = open(self.log_path, "wb")
        self.proc = subprocess.Popen(args, stdout=self._log, stderr=subprocess.STDOUT, start_new_session=True,
                                     env=dict(os.environ, **(env or {})))
        wait_for(lambda: port_open(self.port) or self.proc.poll() is not None, 20, what="rosbridge port")
        assert self.proc.poll() is None, self.log()

    @property
    def pid(self) -> int:
        return self.proc.pid

    def log(self) -> str:
        if not self._log.closed:
            self._log.flush()
        return self.log_path.read_text(errors="replace")

    def threads(self) -> int:
        return len(os.listdir(f"/proc/{self.pid}/task"))

    def rss_kb(self) -> int:
        with open(f"/proc/{self.pid}/status") as f:
            for line in f:
                if line.startswith("VmRSS:"):
                    return int(line.split()[1])
        return 0

    def stop(self, sig: int = signal.SIGINT, timeout: float = 10.0) -> int:
        if self.proc.poll() is None:
            self.proc.send_signal(sig)
            try:
                self.proc.wait(timeout)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait(5)
                raise AssertionError(f"rosbridge did not stop on signal {sig}")
        self._log.close()
        return self.proc.returncode


def node_subscriptions(node: str) -> List[str]:
    import rosgraph
    _, subs, _ = rosgraph.Master("/rb_test").getSystemState()
    return sorted(t for t, nodes in subs if "/" + node.lstrip("/") in nodes)


def node_publications(node: str) -> List[str]:
    import rosgraph
    pubs, _, _ = rosgraph.Master("/rb_test").getSystemState()
    return sorted(t for t, nodes in pubs if "/" + node.lstrip("/") in nodes)


def node_services(node: str) -> List[str]:
    import rosgraph
    _, _, srvs = rosgraph.Master("/rb_test").getSystemState()
    return sorted(s for s, nodes in srvs if "/" + node.lstrip("/") in nodes)


def subscribers_of(topic: str) -> List[str]:
    import rosgraph
    _, subs, _ = rosgraph.Master("/rb_test").getSystemState()
    return next((sorted(n) for t, n in subs if t == topic), [])
