"""What the demo cell's module nodes compute (scripts/vision_node, vision_monitor_node, system_monitor_node), in
plain Python so it is tested without ROS."""
from __future__ import annotations

import io
import os
from typing import Any, Mapping, Optional

from ..diagnostics import OK, WARN, DiagStatus, status as diag_status

DARK = 0.15      # mean brightness (0..1) under which the workbench counts as dark
BRIGHT = 0.9     # over which it counts as overexposed
STALE_S = 3.0    # no brightness for this long: "no image"


def mean_brightness(data: bytes) -> float:
    """Mean grey level of a compressed (JPEG/PNG) image, 0 (black) .. 1 (white)."""
    from PIL import Image, ImageStat

    with Image.open(io.BytesIO(bytes(data))) as img:
        img.thumbnail((160, 160))  # the mean of a small copy is the same to ~1e-3, for a fraction of the time
        return float(ImageStat.Stat(img.convert("L")).mean[0]) / 255.0


def vision_status(brightness: Optional[float], age_s: float) -> str:
    """The vision monitor's verdict on the latest brightness and its age."""
    if brightness is None or age_s > STALE_S:
        return "no image"
    if brightness < DARK:
        return "dark"
    if brightness > BRIGHT:
        return "overexposed"
    return "ok"


def vision_diagnostic(verdict: str, brightness: Optional[float], age_s: float, topic: str) -> DiagStatus:
    """The vision monitor's status on /diagnostics: OK while the verdict is "ok", else WARN with the verdict."""
    values = [("brightness", "-" if brightness is None else f"{brightness:.2f}"),
              ("last brightness (s ago)", "-" if brightness is None else f"{age_s:.1f}"), ("topic", topic)]
    return diag_status("vision: camera brightness", OK if verdict == "ok" else WARN, verdict, values)


def load_diagnostic(load: float) -> DiagStatus:
    """The system monitor's status: WARN above 0.9 per core."""
    return diag_status("system_monitor: CPU load", WARN if load > 0.9 else OK,
                       f"high load: {load:.2f} per core" if load > 0.9 else "normal",
                       [("load per core (1 min)", f"{load:.2f}"), ("cores", os.cpu_count() or 1)])


def stream_topic(cell: Mapping[str, Any], stream: str) -> str:
    """The image topic of the cell file's video stream named `stream` (the first stream when the name is empty)."""
    streams = ((cell.get("video") or {}).get("streams") or [])
    if not streams:
        raise ValueError("the cell file has no video.streams")
    if not stream:
        return streams[0]["topic"]
    for s in streams:
        if s.get("name") == stream:
            return s["topic"]
    raise ValueError(f"no video stream named {stream!r} (the cell has: {', '.join(s.get('name', '?') for s in streams)})")


def load_per_core() -> float:
    """The one-minute load average divided by the number of cores (1.0: every core busy)."""
    return os.getloadavg()[0] / max(1, os.cpu_count() or 1)
