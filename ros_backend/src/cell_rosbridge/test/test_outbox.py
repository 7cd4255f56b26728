"""Per-client send queue semantics: throttle, queue_length drop-oldest, lanes, byte cap."""
from __future__ import annotations

from typing import List

from cell_rosbridge.outbox import CONTROL, ClientOutbox


def make(max_bytes: int = 10_000, default_len: int = 100):
    wakes: List[int] = []
    overflow: List[str] = []
    box = ClientOutbox(max_bytes, default_len, wakeup=lambda: wakes.append(1), on_overflow=overflow.append)
    return box, wakes, overflow


def drain(box: ClientOutbox, now: float = 0.0) -> List[str]:
    out = []
    while True:
        frames, _ = box.pop(now)
        if frames is None:
            return out
        out.extend(frames)


def test_small_queue_length_drops_oldest_of_that_lane_only() -> None:
    box, _, _ = make()
    box.configure_lane("a", queue_length=2, throttle_ms=0)
    box.configure_lane("b", queue_length=0, throttle_ms=0)
    for i in range(5):
        box.push([f"a{i}"], 2, "a")
        box.push([f"b{i}"], 2, "b")
    box.push(["status"], 6, CONTROL)
    assert drain(box) == ["b0", "b1", "b2", "a3", "b3", "a4", "b4", "status"]
    assert box.dropped == 3 and box.queued_bytes == 0


def test_throttle_spaces_messages_and_keeps_newest() -> None:
    box, _, _ = make()
    box.configure_lane("t", queue_length=0, throttle_ms=100)
    box.push(["m1"], 2, "t")
    assert box.pop(10.0) == (["m1"], None)
    box.push(["m2"], 2, "t")
    box.push(["m3"], 2, "t")  # queue_length 0 + throttle: only the newest waits
    frames, delay = box.pop(10.05)
    assert frames is None and abs(delay - 0.05) < 1e-9
    assert box.pop(10.1) == (["m3"], None)


def test_throttle_with_queue_keeps_queue_length_messages() -> None:
    box, _, _ = make()
    box.configure_lane("t", queue_length=3, throttle_ms=50)
    for i in range(5):
        box.push([f"m{i}"], 2, "t")
    got = []
    now = 0.0
    while True:
        frames, delay = box.pop(now)
        if frames is None and delay is None:
            break
        if frames is None:
            now += delay
            continue
        got.append((frames[0], round(now, 3)))
    assert got == [("m2", 0.0), ("m3", 0.05), ("m4", 0.1)]


def test_wakeup_only_once_until_drained() -> None:
    box, wakes, _ = make()
    box.push(["x"], 1)
    box.push(["y"], 1)
    assert len(wakes) == 1
    drain(box)
    box.push(["z"], 1)
    assert len(wakes) == 2


def test_byte_cap_overflow_closes_and_reports_once() -> None:
    box, _, overflow = make(max_bytes=100)
    for _ in range(20):
        box.push(["x" * 10], 10)
    assert len(overflow) == 1 and "100 bytes" in overflow[0]
    assert box.closed and box.queued_bytes == 0
    assert box.pop(0.0) == (None, None)


def test_removed_lane_frees_bytes_and_ignores_late_pushes() -> None:
    box, _, _ = make()
    box.configure_lane("a", 0, 0)
    box.push(["abc"], 3, "a")
    box.remove_lane("a")
    assert box.queued_bytes == 0
    box.push(["late"], 4, "a")
    assert drain(box) == []
