"""Who gets the CPU first on the robot PC (DESIGN "Motion safety"; docs/service.md "Priorities").

The motion path (the arm drivers with their jog dead-man and stop handling, and in simulation the sim, which stands
for the robot's own controller) runs at a raised priority; deferrable work (video encoding, the flight recorder, log
and graph queries, the sim's renderer) runs at a lowered one, so a screen's load makes it late, never the arm.
A raised priority needs CAP_SYS_NICE or a nice limit (the service unit's LimitNICE); without either (an unprivileged
user, a container without the capability) the motion path stays at normal priority and says so once. Lowering is
always allowed. CELL_PRIORITIES=0 turns both off (the load benchmark's comparison run).

On Linux the nice value is per thread: `claim` sets it for every thread the process has and threads started later
inherit it, so it may be called after a library started its own.
"""
from __future__ import annotations

import os
from typing import Callable, Mapping, Optional

MOTION = "motion"
DEFERRABLE = "deferrable"
NICE = {MOTION: -10, DEFERRABLE: 10}

SetNice = Callable[[int, int], None]  # (thread id, nice value); raises OSError


def _threads() -> list[int]:
    try:
        return [int(t) for t in os.listdir("/proc/self/task")]
    except OSError:
        return [0]


def _set_nice(tid: int, nice: int) -> None:
    os.setpriority(os.PRIO_PROCESS, tid, nice)


def claim(role: str, what: str, env: Optional[Mapping[str, str]] = None, set_nice: SetNice = _set_nice,
          threads: Callable[[], list[int]] = _threads) -> str:
    """Give this process the nice value of its role (MOTION or DEFERRABLE); returns the line to log, which says what
    it runs at and, when the OS refused, why and how to allow it."""
    if role not in NICE:
        raise ValueError(f"unknown priority role {role!r} (one of {', '.join(NICE)})")
    env = os.environ if env is None else env
    if env.get("CELL_PRIORITIES", "1") == "0":
        return f"{what}: priorities off (CELL_PRIORITIES=0): normal priority"
    nice = NICE[role]
    try:
        for tid in threads():
            set_nice(tid, nice)
    except PermissionError:
        return (f"{what}: could not raise its priority to nice {nice} (no CAP_SYS_NICE nor a nice limit allowing it): "
                f"it runs at normal priority, and a loaded host can delay it; the service unit (npm run service) "
                f"allows it with LimitNICE")
    except OSError as e:
        return f"{what}: could not set nice {nice} ({e}): it runs at normal priority"
    label = "the motion path, raised" if role == MOTION else "deferrable work, lowered"
    return f"{what}: {label} to nice {nice}"
