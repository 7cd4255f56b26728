"""The motion path raised, deferrable work lowered (cell_nodes.priority): on every thread of a real process, and
what it says when the OS refuses."""
from __future__ import annotations

import os
import resource
import subprocess
import sys
import textwrap

import pytest

from cell_nodes import priority

CHILD = textwrap.dedent("""
    import os, sys, threading
    from cell_nodes import priority
    started = threading.Event(); done = threading.Event()
    threading.Thread(target=lambda: (started.set(), done.wait()), daemon=True).start()  # a library's thread
    started.wait()
    line = priority.claim(sys.argv[1], "test")
    late = threading.Thread(target=done.wait, daemon=True); late.start()  # started after: inherits it
    nices = sorted({int(open(f"/proc/self/task/{t}/stat").read().rsplit(")", 1)[1].split()[16])
                    for t in os.listdir("/proc/self/task")})
    done.set()
    print(line); print(*nices)
""")


def run_child(role: str, **env: str) -> tuple[str, list[int]]:
    out = subprocess.run([sys.executable, "-c", CHILD, role], capture_output=True, text=True, timeout=30,
                         env={**os.environ, **env}, check=True).stdout.splitlines()
    return out[0], [int(n) for n in out[1].split()]


def may_raise() -> bool:
    soft, _ = resource.getrlimit(resource.RLIMIT_NICE)
    return os.geteuid() == 0 or soft == resource.RLIM_INFINITY or 20 - soft <= priority.NICE[priority.MOTION]


def test_deferrable_work_is_lowered_on_every_thread_including_later_ones() -> None:
    line, nices = run_child(priority.DEFERRABLE)
    assert nices == [10] and line == "test: deferrable work, lowered to nice 10"


def test_the_motion_path_is_raised_where_the_os_allows_and_says_so_where_it_does_not() -> None:
    line, nices = run_child(priority.MOTION)
    if may_raise():
        assert nices == [-10] and line == "test: the motion path, raised to nice -10"
    else:
        assert nices == [os.getpriority(os.PRIO_PROCESS, 0)] and "could not raise its priority" in line


def test_a_refused_raise_leaves_normal_priority_and_says_how_to_allow_it() -> None:
    def refuse(_tid: int, _nice: int) -> None:
        raise PermissionError(1, "Operation not permitted")
    line = priority.claim(priority.MOTION, "manual node", env={}, set_nice=refuse, threads=lambda: [1, 2])
    assert line.startswith("manual node: could not raise its priority to nice -10 (no CAP_SYS_NICE")
    assert "LimitNICE" in line and "normal priority" in line


def test_priorities_turned_off_change_nothing() -> None:
    line, nices = run_child(priority.DEFERRABLE, CELL_PRIORITIES="0")
    assert nices == [os.getpriority(os.PRIO_PROCESS, 0)] and "priorities off" in line


def test_an_unknown_role_is_a_programming_error() -> None:
    with pytest.raises(ValueError, match="unknown priority role 'fast'"):
        priority.claim("fast", "x", env={})
