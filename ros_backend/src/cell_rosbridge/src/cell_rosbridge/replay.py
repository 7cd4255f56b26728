"""What a new publisher sent in its first moments, for ROS subscribers whose connection is not up yet.

Why: a ROS subscriber that already exists learns about a new publisher only through the master, and
connects some milliseconds later; whatever the publisher sends before that is lost. A browser that
advertises a topic and publishes at once (or publishes without advertising) hits exactly that window.

The buffer is pure bookkeeping (no ROS, no lock: the caller serialises access; plumbing_ros1 does so
under the rospy publisher's own lock). Each kept message remembers the peers (subscriber connections)
it already reached, so a peer never gets a message twice, and nothing is kept or replayed once the
window after the publisher's creation has ended.
"""
from __future__ import annotations

import time
from collections import deque
from dataclasses import dataclass, field
from typing import Any, Callable, Deque, Generic, Hashable, Iterable, List, Set, TypeVar

M = TypeVar("M")


@dataclass
class _Kept(Generic[M]):
    msg: M
    reached: Set[Hashable] = field(default_factory=set)


class ReplayBuffer(Generic[M]):
    def __init__(self, window: float = 1.0, max_messages: int = 100,
                 clock: Callable[[], float] = time.monotonic) -> None:
        self._clock = clock
        self._closes_at = clock() + window  # the window starts when the publisher is created
        self._kept: Deque[_Kept[M]] = deque(maxlen=max(1, max_messages))  # oldest dropped first
        self._open = window > 0 and max_messages > 0

    def is_open(self) -> bool:
        """True while the window lasts; the first call after it frees the kept messages."""
        if self._open and self._clock() >= self._closes_at:
            self.close()
        return self._open

    def close(self) -> None:
        self._open = False
        self._kept.clear()

    def __len__(self) -> int:
        return len(self._kept)

    def record(self, msg: M, reached: Iterable[Hashable]) -> bool:
        """Keep `msg`, sent just now to the peers in `reached`; False (nothing kept) after the window."""
        if not self.is_open():
            return False
        self._kept.append(_Kept(msg, set(reached)))
        return True

    def missed(self, peer: Hashable, skip: Any = None) -> List[M]:
        """The kept messages `peer` has not got, oldest first; from now on they count as delivered to it.

        `skip` (compared by identity) is marked as delivered without being returned: rospy itself sends
        a latching publisher's last message to every new connection right after the replay.
        """
        if not self.is_open():
            return []
        out: List[M] = []
        for kept in self._kept:
            if peer in kept.reached:
                continue
            kept.reached.add(peer)
            if skip is None or kept.msg is not skip:
                out.append(kept.msg)
        return out
