"""Fixtures for the simulator suite: run `python -m sim` as a real process, the way `npm start` does."""
from __future__ import annotations

import os
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path
from typing import Callable, Iterator, Optional

import pytest

ROOT = Path(__file__).resolve().parents[2]
NO_MASTER = "http://127.0.0.1:1"   # a ROS master URI where none answers


def sim_env(master: str = NO_MASTER, env: Optional[dict[str, str]] = None) -> dict[str, str]:
    """The environment a test's sim runs in: this process's, with the ROS master `master` (none by default) and the
    demo cell unless the test passes --cell or CELL_CONFIG in `env` (never the caller's CELL_CONFIG)."""
    e = dict(os.environ, ROS_MASTER_URI=master)
    e.pop("CELL_CONFIG", None)
    e.update(env or {})
    return e


def port_open(host: str, port: int) -> bool:
    try:
        with socket.create_connection((host, port), timeout=0.2):
            return True
    except OSError:
        return False


class SimProcess:
    def __init__(self, host: str, args: list[str], env: dict[str, str]) -> None:
        self.host = host
        self.log_path = Path(os.environ.get("TMPDIR", "/tmp")) / f"sim-{host}-{os.getpid()}-{time.monotonic_ns()}.log"
        self.log = open(self.log_path, "w")
        self.proc = subprocess.Popen([sys.executable, "-m", "sim", "--host", host, *args], cwd=ROOT, env=env,
                                     stdout=self.log, stderr=subprocess.STDOUT, start_new_session=True)

    def wait_ready(self, timeout: float = 30.0) -> None:
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if self.proc.poll() is not None:
                raise AssertionError(f"sim exited early ({self.proc.returncode}):\n{self.output()}")
            if port_open(self.host, 30004) and port_open(self.host, 29999) and port_open(self.host, 30003):
                return
            time.sleep(0.05)
        raise AssertionError(f"sim on {self.host} not ready after {timeout}s:\n{self.output()}")

    def output(self) -> str:
        if not self.log.closed:
            self.log.flush()
        return self.log_path.read_text()

    def stop(self, sig: int = signal.SIGTERM) -> float:
        """Signal the process and return how long it took to exit."""
        t0 = time.monotonic()
        if self.proc.poll() is None:
            self.proc.send_signal(sig)
            try:
                self.proc.wait(10)
            except subprocess.TimeoutExpired:
                os.killpg(self.proc.pid, signal.SIGKILL)
                self.proc.wait(5)
        self.log.close()
        return time.monotonic() - t0


@pytest.fixture
def start_sim() -> Iterator[Callable[..., SimProcess]]:
    """Factory: start_sim(host, *args, env=None) -> a ready SimProcess; all are stopped (SIGTERM) at teardown."""
    procs: list[SimProcess] = []

    def start(host: str, *args: str, env: Optional[dict[str, str]] = None) -> SimProcess:
        sim = SimProcess(host, list(args), sim_env(env=env))
        procs.append(sim)
        sim.wait_ready()
        return sim

    yield start
    for p in procs:
        took = p.stop()
        assert took < 2.0, f"sim on {p.host} took {took:.2f}s to exit on SIGTERM"
        assert "Traceback" not in p.output(), f"sim on {p.host} logged an exception:\n{p.output()[-3000:]}"


@pytest.fixture(scope="module")
def module_sim(request) -> Iterator[SimProcess]:
    """One sim per test module; the module sets SIM_HOST and SIM_ARGS."""
    host = getattr(request.module, "SIM_HOST")
    args = getattr(request.module, "SIM_ARGS", [])
    sim = SimProcess(host, list(args), sim_env())
    sim.wait_ready()
    yield sim
    took = sim.stop()
    assert took < 2.0, f"sim took {took:.2f}s to exit"
    assert "Traceback" not in sim.output(), f"sim logged an exception:\n{sim.output()[-3000:]}"
