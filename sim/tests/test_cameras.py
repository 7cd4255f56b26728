"""Cameras render only the views somebody watches (a phone shows one stream at a time)."""
from __future__ import annotations

import threading

import pytest

from conftest import wait_for
from sim.cameras import CameraRig
from sim.world import World


class _Controller:
    lock = threading.Lock()


def test_only_watched_cameras_are_rendered() -> None:
    world = World(seed=0)
    rig = CameraRig(world, (96, 72), rate=20.0)
    watched: set[str] = {"workbench"}
    got: list[str] = []
    rig.start(_Controller(), lambda name, jpeg: got.append(name), lambda: watched)
    try:
        wait_for(lambda: got.count("workbench") >= 5, 60, what="workbench frames")
        assert set(got) == {"workbench"}

        watched = set()
        # A frame already in flight may still arrive; after that, nothing for many periods.
        before = len(got)
        wait_for_quiet(lambda: len(got) > before, 0.3)
        n = len(got)
        cycles = rig.frames
        assert n - before <= 1
        assert not wait_for_quiet(lambda: len(got) > n, 0.5)
        assert rig.frames == cycles

        watched = {"global"}
        wait_for(lambda: got[n:].count("global") >= 3, 30, what="global frames")
        assert set(got[n:]) == {"global"}
    finally:
        rig.stop()
        world.close()


def test_a_raw_stream_gets_its_size_of_pixels_and_no_jpeg_is_made_for_it() -> None:
    """A raw (sensor_msgs/Image) stream at 1280x720 from a 96x72 render: the centre cut to 16:9, scaled up."""
    world = World(seed=0)
    rig = CameraRig(world, (96, 72), rate=20.0)
    jpegs: list[str] = []
    raws: list[tuple[str, tuple[int, int], int]] = []

    class Raw:
        def wanted(self):
            return {"global": {(1280, 720)}}

        def publish(self, view, size, pixels):
            raws.append((view, size, len(pixels)))

    rig.start(_Controller(), lambda name, jpeg: jpegs.append(name), lambda: set(), Raw())
    try:
        wait_for(lambda: len(raws) >= 3, 60, what="raw frames")
        assert set(raws) == {("global", (1280, 720), 1280 * 720 * 3)}
        assert jpegs == []
    finally:
        rig.stop()
        world.close()


def test_raw_pixels_keep_the_aspect_of_the_size_asked() -> None:
    import numpy as np
    from sim.cameras import raw_pixels
    img = np.zeros((90, 160, 3), np.uint8)
    img[:, :30] = 255            # a white band on the left, cut away for a 1:1 picture (columns 35..124)
    square = np.frombuffer(raw_pixels(img, (90, 90)), np.uint8).reshape(90, 90, 3)
    assert square.max() == 0
    wide = np.frombuffer(raw_pixels(img, (320, 180)), np.uint8).reshape(180, 320, 3)
    assert wide[:, :50].min() == 255 and wide[:, 70:].max() == 0


def test_a_render_process_that_dies_is_started_again() -> None:
    """A crash in the GL stack (a soak once saw the EGL renderer segfault) must not leave the cell without cameras."""
    import os
    import signal
    world = World(seed=0)
    rig = CameraRig(world, (96, 72), rate=20.0)
    got: list[str] = []
    rig.start(_Controller(), lambda name, jpeg: got.append(name), lambda: {"workbench"})
    try:
        wait_for(lambda: len(got) >= 3, 60, what="frames")
        first = rig.proc.pid
        os.kill(first, signal.SIGKILL)
        wait_for(lambda: rig.restarts == 1 and rig.proc.pid != first, 30, what="a new render process")
        n = len(got)
        wait_for(lambda: len(got) >= n + 3, 60, what="frames from the new render process")
    finally:
        rig.stop()
        world.close()
    assert not rig.proc.is_alive()


def wait_for_quiet(predicate, seconds: float) -> bool:
    """True as soon as `predicate` holds within `seconds`; False if it never does (what this test wants)."""
    try:
        wait_for(predicate, seconds, what="a frame")
        return True
    except AssertionError:
        return False


def test_rig_refuses_a_view_the_sim_does_not_have() -> None:
    with pytest.raises(ValueError, match="ceiling"):
        CameraRig(None, (96, 72), rate=20.0, views=["workbench", "ceiling"])  # before any process starts


def test_a_camera_reports_its_frame_rate_and_a_watched_camera_without_frames_warns() -> None:
    from sim.cell_file import Stream
    from sim.ros_bridge import camera_diagnostic
    s = Stream(name="Bench", topic="/bench/compressed", view="workbench")
    level, name, message, values = camera_diagnostic("sim_cell", s, [9.0 + i / 6 for i in range(12)], True, 11.0)
    assert (level, name, message) == (0, "sim_cell: camera Bench", "streaming at 6.0 fps")
    assert dict(values)["frame rate (fps)"] == "6.0" and dict(values)["topic"] == "/bench/compressed"
    assert camera_diagnostic("sim_cell", s, [1.0], True, 11.0)[:3] == (1, "sim_cell: camera Bench",
                                                                     "no frame for 2 s while watched")
    assert camera_diagnostic("sim_cell", s, [], False, 11.0)[2] == "idle: no subscriber"
