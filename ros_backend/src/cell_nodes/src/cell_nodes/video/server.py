"""The video node's logic without ROS: the cell file's raw streams, one JPEG output topic per size and quality
asked for, the camera subscribed only while an output has a viewer, each frame decoded once and encoded once per
frame size, and each stream's status for the viewers. ROS comes in through the callables given to VideoServer."""
from __future__ import annotations

import re
import threading
import time
from collections import deque
from dataclasses import dataclass, field
from typing import Any, Callable, Mapping, Optional, Protocol

from ..diagnostics import ERROR, OK, WARN, DiagStatus
from .images import FrameError, Size, frame_size, jpeg, picture, wanted

NS = "/cell/video"
NO_FRAME_S = 3.0        # a watched camera without a frame for this long is reported (the viewer marks it stale)
LINGER_S = 2.0          # the camera stays subscribed this long after its last viewer left (a viewer switching sizes)
OUTPUT_IDLE_S = 60.0    # an output topic nobody watched for this long is unadvertised


class ConfigError(ValueError):
    pass


class Publisher(Protocol):
    def subscriber_count(self) -> int: ...
    def publish(self, msg: Any) -> Any: ...
    def close(self) -> Any: ...


class Subscription(Protocol):
    def close(self) -> Any: ...


@dataclass(frozen=True)
class RawStream:
    name: str
    topic: str


def raw_streams(cell: Mapping[str, Any]) -> list[RawStream]:
    """The cell file's `video.streams` whose `type` is raw (sensor_msgs/Image)."""
    video = cell.get("video") or {}
    if not isinstance(video, dict) or not isinstance(video.get("streams") or [], list):
        raise ConfigError("video.streams: expected a list")
    out = []
    for i, s in enumerate(video.get("streams") or []):
        if not isinstance(s, dict) or not isinstance(s.get("topic"), str):
            raise ConfigError(f"video.streams[{i}]: expected a mapping with a topic")
        if s.get("type", "compressed") == "raw":
            out.append(RawStream(str(s.get("name") or s["topic"]), s["topic"]))
    return out


def output_topic(source: str, want: Size) -> str:
    slug = re.sub(r"[^A-Za-z0-9]+", "_", source).strip("_") or "camera"
    return f"{NS}/{slug}/{'w' + str(want.width) if want.width else 'full'}_q{want.quality}"


@dataclass
class Answer:
    ok: bool
    message: str = ""
    topic: str = ""
    width: int = 0
    height: int = 0
    quality: int = 0


@dataclass
class _Output:
    want: Size
    topic: str
    pub: Publisher
    idle_since: Optional[float] = None


@dataclass
class _Camera:
    spec: RawStream
    outputs: dict[Size, _Output] = field(default_factory=dict)
    sub: Optional[Subscription] = None
    unwatched_since: Optional[float] = None
    source: Optional[tuple[int, int]] = None
    encoding: str = ""
    error: str = ""
    subscribed_at: float = 0.0
    frames: deque = field(default_factory=lambda: deque(maxlen=120))
    encoded: int = 0


class VideoServer:
    """`advertise(topic)` makes a CompressedImage publisher; `subscribe(topic, cb)` subscribes to a raw camera;
    `to_msg(source_msg, jpeg_bytes)` makes the CompressedImage (with the source's header, so its age is the
    camera's). Requests, frames and tick() may come from different threads."""

    def __init__(self, streams: list[RawStream], advertise: Callable[[str], Publisher],
                 subscribe: Callable[[str, Callable[[Any], None]], Subscription],
                 to_msg: Callable[[Any, bytes], Any], clock: Callable[[], float] = time.monotonic) -> None:
        self._cams = {s.topic: _Camera(s) for s in streams}
        self._advertise, self._subscribe, self._to_msg, self._clock = advertise, subscribe, to_msg, clock
        self._lock = threading.Lock()

    def request(self, topic: str, width: int, quality: int) -> Answer:
        cam = self._cams.get(topic)
        if cam is None:
            return Answer(False, f"{topic or '(no topic)'} is not a raw camera stream of the cell file")
        want = wanted(width, quality)
        with self._lock:
            if cam.source is not None:   # the camera's size is known: never larger than it
                w, _ = frame_size(want, cam.source)
                want = Size(0 if w == cam.source[0] else w, want.quality)
            out = cam.outputs.get(want)
            if out is None:
                name = output_topic(topic, want)
                out = cam.outputs[want] = _Output(want, name, self._advertise(name), idle_since=self._clock())
            w, h = frame_size(want, cam.source) if cam.source else (0, 0)
            return Answer(True, cam.error, out.topic, w, h, want.quality)

    def on_frame(self, topic: str, msg: Any) -> None:
        """One sensor_msgs/Image of a camera: decoded once, encoded once per frame size and quality watched."""
        cam = self._cams[topic]
        now = self._clock()
        with self._lock:
            watched = [o for o in cam.outputs.values() if o.pub.subscriber_count() > 0]
        try:
            img = picture(msg.encoding, int(msg.width), int(msg.height), int(msg.step), msg.data,
                          bool(msg.is_bigendian))
        except FrameError as e:
            cam.error = str(e)
            return
        cam.error, cam.encoding = "", msg.encoding
        cam.source = (int(msg.width), int(msg.height))
        cam.frames.append(now)
        done: dict[tuple[tuple[int, int], int], Any] = {}
        for out in watched:
            key = (frame_size(out.want, cam.source), out.want.quality)
            if key not in done:
                done[key] = self._to_msg(msg, jpeg(img, key[0], key[1]))
                cam.encoded += 1
            out.pub.publish(done[key])

    def tick(self) -> list[DiagStatus]:
        """Subscribe the cameras somebody watches, leave the others, drop outputs idle for long; each stream's
        status."""
        now = self._clock()
        statuses = []
        for cam in self._cams.values():
            with self._lock:
                watched = False
                for key, out in list(cam.outputs.items()):
                    if out.pub.subscriber_count() > 0:
                        watched, out.idle_since = True, None
                    elif out.idle_since is None:
                        out.idle_since = now
                    elif now - out.idle_since > OUTPUT_IDLE_S:
                        out.pub.close()
                        del cam.outputs[key]
                if watched:
                    cam.unwatched_since = None
                    if cam.sub is None:
                        cam.sub = self._subscribe(cam.spec.topic, lambda m, t=cam.spec.topic: self.on_frame(t, m))
                        cam.subscribed_at = now
                elif cam.sub is not None:
                    if cam.unwatched_since is None:
                        cam.unwatched_since = now
                    elif now - cam.unwatched_since >= LINGER_S:
                        cam.sub.close()
                        cam.sub, cam.unwatched_since = None, None
            statuses.append(self._status(cam, now))
        return statuses

    def _status(self, cam: _Camera, now: float) -> DiagStatus:
        recent = [t for t in cam.frames if t >= now - 2.0]
        fps = len(recent) / 2.0
        size = f"{cam.source[0]}x{cam.source[1]} {cam.encoding}" if cam.source else "size not known yet"
        values = (("topic", cam.spec.topic), ("source", size), ("fps", f"{fps:.1f}"),
                  ("outputs", ", ".join(sorted(o.topic for o in cam.outputs.values()))), ("encoded", str(cam.encoded)))
        name = f"video: {cam.spec.name}"
        if cam.error:
            return DiagStatus(name, ERROR, cam.error, cam.spec.topic, values)
        if cam.sub is None:
            return DiagStatus(name, OK, "not watched", cam.spec.topic, values)
        last = cam.frames[-1] if cam.frames else cam.subscribed_at
        if now - last > NO_FRAME_S:
            return DiagStatus(name, WARN, f"no frame from {cam.spec.topic} for {now - last:.0f} s", cam.spec.topic, values)
        return DiagStatus(name, OK, f"{size} at {fps:.1f} fps", cam.spec.topic, values)
