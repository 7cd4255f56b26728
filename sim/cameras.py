"""The sim's camera viewpoints (VIEWS), rendered in a separate process so physics keeps real time.

The cell file's video streams choose among these viewpoints and the cell's own (`simulation.views`,
sim/cell_file.py); several streams may show one viewpoint, which is then rendered once. The render process holds a replica of the cell (same construction
code, no physics stepping). At the camera rate the main process sends it a snapshot of joint positions and
part poses and the viewpoints wanted; it renders those (EGL renderer plugin when it loads, TinyRenderer
otherwise), JPEG-encodes them and sends the bytes back; for a raw stream (`type: raw`) it sends the pixels at
that stream's size instead (rgb8, the render cut to its aspect and scaled).
"""
from __future__ import annotations

import io
import logging
import multiprocessing as mp
import threading
import time
from dataclasses import dataclass
from typing import Callable, Iterable, Optional, Protocol

from .pacing import Pacer

log = logging.getLogger("sim.cameras")

JPEG_QUALITY = 80
RENDER_NICE = 10


@dataclass(frozen=True)
class CameraSpec:
    name: str
    eye: tuple[float, float, float]
    target: tuple[float, float, float]
    fov: float = 60.0


# The one table of viewpoints. Order matters: video streams without `view` get them in this order (cycling).
VIEWS: dict[str, CameraSpec] = {cam.name: cam for cam in (
    CameraSpec("workbench", eye=(-0.95, 0.05, 0.75), target=(-0.4, 0.05, 0.0), fov=55.0),
    CameraSpec("global", eye=(1.1, -1.5, 1.3), target=(-0.25, 0.0, 0.15), fov=60.0),
)}


def viewpoints(world_spec=None) -> dict[str, CameraSpec]:
    """The built-in viewpoints, then the world's own (`simulation.views`)."""
    out = dict(VIEWS)
    for v in getattr(world_spec, "views", ()) or ():
        out[v.name] = CameraSpec(v.name, tuple(v.eye), tuple(v.target), v.fov)
    return out


def _render_main(conn, seed: int, urdf_dir: str, size: tuple[int, int], world_spec=None) -> None:
    """Render process: build the replica, then answer (snapshot, view names) -> [(view, jpeg, ms)] until told to stop."""
    import os
    import signal
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C reaches the whole group: the parent stops us
    # Budget the renderer: a lower priority lets the controller loop win whenever both want the CPU
    # (Mesa's llvmpipe may use every core; LP_NUM_THREADS=1 confines it further at a cost in frame rate).
    try:  # absolute: the sim's own (raised) priority is inherited
        os.setpriority(os.PRIO_PROCESS, 0, RENDER_NICE)
    except OSError:
        pass
    import numpy as np
    import pybullet
    from PIL import Image

    from .scene import DEFAULT_WORLD
    from .world import World

    if getattr(world_spec, "kind", None) == "ros_control":  # the ros_control cell's arm (sim/ros_control/world.py)
        from .ros_control.world import IiwaWorld as World  # noqa: F811
    world = World(seed=seed, render_only=True, urdf_dir=urdf_dir, spec=world_spec or DEFAULT_WORLD)
    p = world.p
    renderer = pybullet.ER_BULLET_HARDWARE_OPENGL if world.egl else pybullet.ER_TINY_RENDERER
    w, h = size
    views = []
    for cam in viewpoints(world_spec).values():
        views.append((cam.name, p.computeViewMatrix(cam.eye, cam.target, (0, 0, 1)),
                      p.computeProjectionMatrixFOV(fov=cam.fov, aspect=w / h, nearVal=0.05, farVal=6.0)))
    conn.send(("ready", "egl" if renderer == pybullet.ER_BULLET_HARDWARE_OPENGL else "tiny"))
    while True:
        msg = conn.recv()
        if msg is None:
            break
        snapshot, wanted, raw = msg
        world.apply_snapshot(snapshot)
        frames = []
        for name, view, projection in views:
            if name not in wanted and name not in raw:
                continue
            t0 = time.perf_counter()
            _, _, rgba, _, _ = p.getCameraImage(w, h, view, projection, renderer=renderer,
                                                flags=pybullet.ER_NO_SEGMENTATION_MASK)
            img = np.reshape(np.asarray(rgba, dtype=np.uint8), (h, w, 4))[:, :, :3]
            encoded = b""
            if name in wanted:
                buf = io.BytesIO()
                Image.fromarray(img).save(buf, format="JPEG", quality=JPEG_QUALITY)
                encoded = buf.getvalue()
            raws = {size: raw_pixels(img, size) for size in raw.get(name, ())}
            frames.append((name, encoded, (time.perf_counter() - t0) * 1000, raws))
        conn.send(frames)
    world.close()


class RawOutputs(Protocol):
    """The raw (sensor_msgs/Image) cameras of the cell: which sizes of which viewpoint someone watches, and where
    their pixels go."""
    def wanted(self) -> dict[str, set[tuple[int, int]]]: ...
    def publish(self, view: str, size: tuple[int, int], pixels: bytes) -> None: ...


def raw_pixels(img, size: tuple[int, int]) -> bytes:
    """A rendered picture (h, w, 3 uint8) as a raw camera of `size` gives it (rgb8 rows): the centre cut to that
    size's aspect, then scaled (the renderer draws at the camera size; a 720p picture would take it 3x longer)."""
    import numpy as np
    from PIL import Image
    h, w = img.shape[:2]
    tw, th = size
    if tw * h > th * w:     # wider than the render: cut rows
        ch = max(1, round(w * th / tw))
        img = img[(h - ch) // 2:(h - ch) // 2 + ch]
    else:
        cw = max(1, round(h * tw / th))
        img = img[:, (w - cw) // 2:(w - cw) // 2 + cw]
    out = Image.fromarray(np.ascontiguousarray(img))
    if out.size != size:
        out = out.resize(size, Image.BILINEAR)
    return out.tobytes()


class CameraRig:
    """Drives the render process at the camera rate and hands JPEG frames (per viewpoint) to a publisher callback."""

    def __init__(self, world, size: tuple[int, int], rate: float, speed: float = 1.0,
                 views: Optional[Iterable[str]] = None) -> None:
        """`views`: the viewpoints the cell's streams use (None: all of them); others are never rendered."""
        known = viewpoints(getattr(world, "spec", None))
        self.views = set(known if views is None else views)
        unknown = self.views - set(known)
        if unknown:
            raise ValueError(f"unknown camera views: {sorted(unknown)}")
        self.world = world
        self.size = size
        self.period = 1.0 / rate
        self.restarts = 0
        self._spawn()
        self._stop = threading.Event()
        self._thread: Optional[threading.Thread] = None
        self.renderer = "?"
        self.ready = False
        self.frames = 0
        self.render_ms: list[float] = []
        self.last: dict[str, bytes] = {}
        self._raw: Optional[RawOutputs] = None

    def start(self, controller, publish: Optional[Callable[[str, bytes], None]],
              watched: Optional[Callable[[], set[str]]] = None, raw: Optional["RawOutputs"] = None) -> None:
        """`watched` names the viewpoints someone subscribes to as JPEG (None: all of them); `raw` the raw images
        someone subscribes to. Only those are rendered."""
        self._raw = raw
        self._thread = threading.Thread(target=self._loop, args=(controller, publish, watched), name="cameras", daemon=True)
        self._thread.start()

    def _spawn(self) -> None:
        ctx = mp.get_context("spawn")  # fork would copy the physics client and running threads
        self.conn, child = ctx.Pipe()
        w = self.world
        self.proc = ctx.Process(target=_render_main, args=(child, w.seed, w.urdf_dir, self.size, w.spec),
                                name="sim-cameras", daemon=True)
        self.proc.start()

    def _loop(self, controller, publish, watched) -> None:
        # A renderer that dies (a crash in the GL stack: a soak once saw llvmpipe's EGL renderer segfault after
        # minutes) is started again, a little later each time, rather than leaving the cell without cameras.
        while True:
            try:
                self._render_frames(controller, publish, watched)
                return
            except (EOFError, OSError, ValueError) as e:  # the render process went away (normally: stopping)
                if self._stop.is_set():
                    return
                self.restarts += 1
                log.error("camera process lost (%s, exit code %s): starting it again", e or type(e).__name__,
                          self.proc.exitcode)
                self.ready = False
                self._end_process()
                if self._stop.wait(min(10.0, float(self.restarts))):
                    return
                self._spawn()

    def _render_frames(self, controller, publish, watched) -> None:
        deadline = time.monotonic() + 60
        while not self.conn.poll(0.05):
            if self._stop.is_set():
                return
            if time.monotonic() > deadline or not self.proc.is_alive():
                raise EOFError("the camera process did not start")
        _, self.renderer = self.conn.recv()
        self.ready = True
        log.info("cameras: %dx%d at %.3g Hz, renderer %s", self.size[0], self.size[1], 1 / self.period, self.renderer)
        pacer = Pacer(self.period, self._stop)
        while not self._stop.is_set():
            # Rendering is the costliest thing the cell does: skip the views nobody watches.
            wanted = self.views if watched is None else set(watched()) & self.views
            raw = {v: sizes for v, sizes in (self._raw.wanted() if self._raw else {}).items() if v in self.views and sizes}
            if not wanted and not raw:
                pacer.wait()
                continue
            with controller.lock:  # the physics client is not thread-safe
                snap = self.world.snapshot()
            self.conn.send((snap, wanted, raw))
            while not self.conn.poll(0.05):
                if self._stop.is_set():
                    return
                if not self.proc.is_alive():
                    raise EOFError("the camera process exited")
            frames = self.conn.recv()
            for name, jpeg, ms, raws in frames:
                self.render_ms.append(ms)
                try:
                    if jpeg:
                        self.last[name] = jpeg
                        if publish is not None:
                            publish(name, jpeg)
                    for size, pixels in raws.items():
                        assert self._raw is not None
                        self._raw.publish(name, size, pixels)
                except Exception:
                    log.exception("image publish failed")
            self.frames += 1
            pacer.wait()

    def signal_stop(self) -> None:
        self._stop.set()

    def stop(self) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join(0.2)
        if self.ready:
            try:
                self.conn.send(None)
            except (OSError, BrokenPipeError):
                pass
            self.proc.join(0.2)
        self._end_process()

    def _end_process(self) -> None:
        if self.proc.is_alive():  # still starting up or stuck in a frame: it holds no state worth saving
            self.proc.terminate()
            self.proc.join(0.3)
        if self.proc.is_alive():
            self.proc.kill()
        self.proc.join(0.2)
