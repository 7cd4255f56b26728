"""A module's output, bounded: the last lines of its nodes' stdout/stderr log files (modules the launcher started),
or of their /rosout messages (modules started elsewhere), merged in time order and tagged with the node name."""
from __future__ import annotations

import collections
import os
import re
import threading
from dataclasses import dataclass
from typing import Iterable, Optional, Sequence

MAX_LINES = 200          # the most lines one output request returns
TAIL_BYTES = 64 * 1024   # read at most this much of the end of each log file
MAX_LINE_CHARS = 500     # longer lines are cut (a line is for a phone screen, not a data dump)
# rospy's console lines: `[INFO] [1718000000.123456]: text`; roscpp: `[ INFO] [1718000000.123456789]: text`
_STAMP = re.compile(r"^\[\s*[A-Z]+\]\s*\[(\d+\.\d+)")


def clamp_lines(n: int) -> int:
    """The number of lines a request may ask for: 1..MAX_LINES (0 or less means MAX_LINES)."""
    return MAX_LINES if n <= 0 else min(int(n), MAX_LINES)


def _cut(line: str) -> str:
    line = line.rstrip("\r\n")
    return line if len(line) <= MAX_LINE_CHARS else line[:MAX_LINE_CHARS - 1] + "…"


def tail_file(path: str, n: int, max_bytes: int = TAIL_BYTES) -> list[str]:
    """The last `n` lines of a file, reading at most `max_bytes` from its end ([] when it does not exist)."""
    try:
        with open(path, "rb") as f:
            f.seek(0, os.SEEK_END)
            size = f.tell()
            f.seek(max(0, size - max_bytes))
            data = f.read(max_bytes)
    except OSError:
        return []
    lines = data.decode("utf-8", "replace").splitlines()
    if size > max_bytes and lines:
        lines = lines[1:]  # the first one is probably cut
    return [_cut(x) for x in lines[-n:] if x.strip()] if n > 0 else []


@dataclass(frozen=True)
class Stream:
    """One log file of one node process."""
    tag: str      # what each line is prefixed with: `[vision]`, `[vision stderr]`
    path: str


@dataclass(frozen=True)
class Line:
    stamp: float
    text: str


def stream_lines(stream: Stream, n: int) -> list[Line]:
    """The last `n` lines of a stream, each with a time: its own console stamp when it has one, else the stamp of
    the line before it (a traceback after an error line), else the file's modification time."""
    raw = tail_file(stream.path, n)
    if not raw:
        return []
    try:
        mtime = os.path.getmtime(stream.path)
    except OSError:
        mtime = 0.0
    stamps: list[Optional[float]] = []
    for text in raw:
        m = _STAMP.match(text)
        stamps.append(float(m.group(1)) if m else None)
    first = next((s for s in stamps if s is not None), mtime)
    out, last = [], first
    for text, s in zip(raw, stamps):
        last = s if s is not None else last
        out.append(Line(last, f"{stream.tag} {text}"))
    return out


def merge(groups: Iterable[Sequence[Line]], n: int) -> list[str]:
    """Merge time-stamped lines of several streams (stable within a stream) and keep the last `n`."""
    keyed = [(line.stamp, g, i, line.text) for g, lines in enumerate(groups) for i, line in enumerate(lines)]
    keyed.sort(key=lambda k: (k[0], k[1], k[2]))
    return [k[3] for k in keyed[-n:]] if n > 0 else []


class RosoutBuffer:
    """The last MAX_LINES /rosout messages of each node we watch (thread-safe)."""

    def __init__(self, nodes: Iterable[str], per_node: int = MAX_LINES) -> None:
        self._buf: dict[str, collections.deque[Line]] = {n: collections.deque(maxlen=per_node) for n in nodes}
        self._lock = threading.Lock()

    def add(self, node: str, level: str, stamp: float, text: str) -> None:
        buf = self._buf.get(node)
        if buf is None:
            return
        tag = f"[{node.lstrip('/')}]"
        first, *rest = text.splitlines() or [""]
        with self._lock:
            buf.append(Line(stamp, _cut(f"{tag} [{level}] [{stamp:.6f}]: {first}")))
            buf.extend(Line(stamp, _cut(f"{tag} {x}")) for x in rest if x.strip())

    def lines(self, nodes: Iterable[str]) -> list[list[Line]]:
        with self._lock:
            return [list(self._buf.get(n, ())) for n in nodes]
