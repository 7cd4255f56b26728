"""Manual motion against the simulated UR controller (sim/) through the unmodified ur_rtde client: the driver core
with its real connector, measured from outside with a separate RTDE receive client, as one would watch a real arm.

The sims run on their own loopback addresses (ur_rtde's ports are fixed) at real-time speed, so the stop times and
TCP speeds measured here are wall-clock figures.
"""
from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path
from typing import Callable, Iterator

import numpy as np
import pytest
import rtde_receive
import yaml

from cell_nodes.manual import frames
from cell_nodes.manual.config import UR_JOINTS, parse_manual
from cell_nodes.manual.ur_process import UrRtdeConnector
from cell_nodes.manual.driver import ManualDriver
from cell_nodes.manual.limits import Limits
from conftest import wait_for
from nodes_helpers import start_sim

HOST = "127.0.0.51"          # the module's sim
RESTART_HOST = "127.0.0.52"  # the reconnection test's own sim
SLOW_HOST = "127.0.0.53"     # a controller slow to start programs
FREEZE_HOST = "127.0.0.54"   # the frozen-controller test's own sim
SECTION = yaml.safe_load((Path(__file__).resolve().parents[4] / "config" / "demo-cell.yaml").read_text())["manual"]
CONFIGS = {name: list(q) for name, q in SECTION["groups"][0]["configurations"].items()}
HEARTBEAT_S = 0.05           # the page's jog heartbeat period


def make_driver(host: str) -> ManualDriver:
    cfg = parse_manual(SECTION)
    d = ManualDriver(cfg, host, UrRtdeConnector(), Limits.from_section(cfg.limits))
    d.start()
    wait_for(lambda: d.connected and d.snapshot().q, 10, what="driver connected")
    return d


SIMS: dict[str, object] = {}  # the module's sim, for tests that read its log


@pytest.fixture(scope="module")
def cell() -> Iterator[tuple[ManualDriver, rtde_receive.RTDEReceiveInterface]]:
    sim = SIMS[HOST] = start_sim(HOST, "--no-ros", "--no-cameras")
    driver = make_driver(HOST)
    watch = rtde_receive.RTDEReceiveInterface(HOST)
    try:
        yield driver, watch
    finally:
        driver.shutdown()
        watch.disconnect()
        sim.stop()
        assert "Traceback" not in sim.output(), sim.output()[-3000:]


def test_the_driver_asks_for_the_state_no_faster_than_it_reads_it(cell) -> None:
    """Each of the driver's clients streams at 125 Hz, its poll rate; the watch client (ur_rtde's default) at 500."""
    out = SIMS[HOST].output()  # type: ignore[attr-defined]
    rates = [float(r) for r in re.findall(r"RTDE: output recipe \d+, \d+ variables at ([\d.]+) Hz", out)]
    assert sorted(rates) == [125.0] * (len(rates) - 1) + [500.0] and len(rates) >= 2, (rates, out[-2000:])


def q_of(watch) -> np.ndarray:
    return np.array(watch.getActualQ())


def speed_of(watch) -> float:
    return float(np.max(np.abs(watch.getActualQd())))


def go_home(driver: ManualDriver) -> None:
    ok, why = driver.move_named("arm", "home", 1.0, 1.5)
    assert ok, why


def test_named_move_arrives_within_10_mrad(cell) -> None:
    driver, watch = cell
    go_home(driver)
    np.testing.assert_allclose(q_of(watch), CONFIGS["home"], atol=0.01)
    states: list[str] = []
    driver.on_change = lambda: states.append(driver.state().motion)
    try:
        ok, why = driver.move_named("arm", "pick_approach", 1.0, 1.5)
    finally:
        driver.on_change = lambda: None
    assert (ok, why) == (True, "arrived at pick_approach")
    err = float(np.max(np.abs(q_of(watch) - CONFIGS["pick_approach"])))
    assert err < 0.01, f"{err:.4f} rad from the configuration"
    assert "moving" in states and driver.state().motion == "idle" and driver.state().progress == 1.0
    assert driver.state().message == "arrived at pick_approach"


def test_relative_z_move_within_1_mm(cell) -> None:
    driver, watch = cell
    go_home(driver)
    start = np.array(watch.getActualTCPPose())
    ok, why = driver.move_relative("arm", [0, 0, 0.05, 0, 0, 0], "base", 0.1, 0.5)
    assert (ok, why) == (True, "arrived at the relative target")
    end = np.array(watch.getActualTCPPose())
    assert np.linalg.norm(end[:3] - (start[:3] + [0, 0, 0.05])) < 0.001
    assert frames.pose_distance(start, end)[1] < 0.005  # orientation kept
    # Tool frame: the tool points down, so +z along the tool goes back down.
    ok, why = driver.move_relative("arm", [0, 0, 0.05, 0, 0, 0], "tool", 0.1, 0.5)
    assert ok, why
    assert np.linalg.norm(np.array(watch.getActualTCPPose())[:3] - start[:3]) < 0.001


def test_unreachable_pose_is_refused_and_the_arm_does_not_move(cell) -> None:
    driver, watch = cell
    # Settled: still for 0.1 s in a row (the tracking of the last move can ring below 1e-3 rad/s for a moment).
    still_since = [time.monotonic()]

    def settled() -> bool:
        if speed_of(watch) >= 1e-3:
            still_since[0] = time.monotonic()
        return time.monotonic() - still_since[0] > 0.1
    wait_for(settled, 5, interval=0.005, what="the arm settled after the last move")
    q0 = q_of(watch)
    far = list(watch.getActualTCPPose())
    far[0] += 3.0  # 3 m away: outside the UR5's reach
    assert driver.move_pose("arm", far) == (False, "pose unreachable: no inverse kinematics solution")
    deadline = time.monotonic() + 0.3
    travel = 0.0
    while time.monotonic() < deadline:  # watch for any motion for a while (nothing to wait for)
        travel = max(travel, float(np.max(np.abs(q_of(watch) - q0))))
        time.sleep(0.01)
    # A started move would travel centimetres in 0.3 s; residual settling is far below a milliradian.
    assert travel < 5e-4, f"the arm moved {travel:.5f} rad after a refused move"
    assert watch.getRuntimeState() == 2  # the control script still runs: no runtime error on the controller
    ok, why = driver.move_relative("arm", [0.02, 0, 0, 0, 0, 0], "base")  # and the next move works
    assert ok, why


def test_the_preview_through_ur_rtde_is_where_the_moves_go(cell) -> None:
    """The move preview against the controller through the unmodified ur_rtde client (the emulated controller answers
    getInverseKinematics, isJointsWithinSafetyLimits and getForwardKinematics): a named configuration and the TCP
    there, a relative move that ends at the previewed joints, an unreachable pose refused with the move's words, and
    an answer while a move runs (which it leaves alone)."""
    driver, watch = cell
    go_home(driver)
    ok, message, names, q, tcp = driver.preview_move("arm", "named", "pick_approach")
    assert (ok, message, names, q) == (True, "pick_approach is reachable", list(UR_JOINTS), CONFIGS["pick_approach"])
    assert driver.move_named("arm", "pick_approach", 1.0, 1.5) == (True, "arrived at pick_approach")
    d, a = frames.pose_distance(watch.getActualTCPPose(), tcp)
    assert d < 0.001 and a < 0.005, f"the TCP ended {d * 1000:.2f} mm, {a:.4f} rad from the previewed pose"

    go_home(driver)
    offset = [0.03, -0.02, 0.04, 0.0, 0.0, 0.3]
    ok, message, _, q, tcp = driver.preview_move("arm", "relative", offset=offset, frame="tool")
    assert (ok, message) == (True, "the relative target is reachable")
    assert np.max(np.abs(np.array(q) - CONFIGS["home"])) > 0.05   # the joints do change
    assert driver.move_relative("arm", offset, "tool", 0.1, 0.5) == (True, "arrived at the relative target")
    err = float(np.max(np.abs(q_of(watch) - q)))
    print(f"\nrelative move: the arm ended {err * 1000:.3f} mrad from the previewed joints")
    assert err < 0.005
    d, a = frames.pose_distance(watch.getActualTCPPose(), tcp)
    assert d < 0.001 and a < 0.005

    far = list(watch.getActualTCPPose())
    far[0] += 3.0
    assert driver.preview_move("arm", "pose", pose=far) == (
        False, "pose unreachable: no inverse kinematics solution", [], [], [])
    assert watch.getRuntimeState() == 2  # never asked for an IK without a solution: the control script still runs

    result: dict = {}
    mover = threading.Thread(target=lambda: result.setdefault("r", driver.move_named("arm", "home", 0.5, 1.0)))
    mover.start()
    wait_for(lambda: speed_of(watch) > 0.2, 5, interval=0.005, what="the arm moving")
    ok, message, _, q, _ = driver.preview_move("arm", "relative", offset=[0, 0, 0.02, 0, 0, 0], frame="base")
    assert ok, message
    assert driver.state().motion == "moving" and driver.state().motion_target == "home"
    mover.join(10)
    assert result["r"] == (True, "arrived at home")


def _jog_then(driver: ManualDriver, watch, seconds: float, jog: tuple, sample: Callable[[], None] | None = None
              ) -> float:
    """Hold a jog for `seconds` (heartbeats every 50 ms); returns the time of the last heartbeat."""
    end = time.monotonic() + seconds
    last = time.monotonic()
    while time.monotonic() < end:
        driver.jog(*jog)
        last = time.monotonic()
        next_beat = last + HEARTBEAT_S
        while time.monotonic() < next_beat:
            if sample:
                sample()
            time.sleep(0.002)
    return last


def _time_to_standstill(watch, since: float, limit: float = 2.0) -> float:
    while speed_of(watch) >= 0.01:
        assert time.monotonic() - since < limit, "the arm did not stop"
        time.sleep(0.001)
    return time.monotonic() - since


def test_jog_stops_within_300_ms_when_heartbeats_stop(cell) -> None:
    driver, watch = cell
    go_home(driver)
    jog = ("arm", "joint", 5, 1, 1.0, "base", None, 1)  # wrist 3 at the full slider: 1 rad/s; the page's press 1
    last = _jog_then(driver, watch, 1.0, jog)
    moving = speed_of(watch)
    assert moving > 0.9, f"the jog should run at ~1 rad/s, ran at {moving:.2f}"
    stopped_after = _time_to_standstill(watch, last)
    print(f"\nheartbeats stopped at 1 rad/s: standstill {stopped_after * 1000:.0f} ms after the last heartbeat "
          f"({(stopped_after - 0.2) * 1000:.0f} ms after the 0.2 s timeout)")
    assert stopped_after < 0.3, "standstill later than 300 ms after the last heartbeat"
    assert driver.state().message == "jog stopped: no heartbeat for 0.2 s"
    wait_for(lambda: driver.state().motion == "idle", 1, what="idle")
    # The same press's heartbeats come again (a page that froze and thawed with the button still held): the arm
    # stays where it stopped, as with a teach pendant's enabling switch; only a new press moves it.
    q = watch.getActualQ()[5]
    speeds: list[float] = []
    _jog_then(driver, watch, 0.5, jog, lambda: speeds.append(speed_of(watch)))
    assert max(speeds) < 0.01 and abs(watch.getActualQ()[5] - q) < 0.001, "the stalled press moved the arm again"
    assert driver.state().motion == "idle"
    driver.jog("arm", "joint", 5, 0, 1.0, "base", None, 1)
    # Release (direction 0) of a new press: standstill within 300 ms.
    _jog_then(driver, watch, 0.6, ("arm", "joint", 5, -1, 1.0, "base", None, 2))
    assert speed_of(watch) > 0.9, "a new press did not move the arm"
    t_release = time.monotonic()
    driver.jog("arm", "joint", 5, 0, 1.0, "base")
    released_after = _time_to_standstill(watch, t_release)
    print(f"release at 1 rad/s: standstill after {released_after * 1000:.0f} ms")
    assert released_after < 0.3


def test_cartesian_jog_tcp_speed_at_full_slider_is_at_most_250_mm_s(cell) -> None:
    driver, watch = cell
    go_home(driver)
    ok, why = driver.move_relative("arm", [-0.15, 0, 0, 0, 0, 0], "base", 0.25, 1.0)  # room to jog along +X
    assert ok, why
    speeds: list[float] = []
    sample = lambda: speeds.append(float(np.linalg.norm(watch.getActualTCPSpeed()[:3])))  # noqa: E731
    x0 = watch.getActualTCPPose()[0]
    last = _jog_then(driver, watch, 1.0, ("arm", "cartesian", 0, 1, 1.0, "base"), sample)
    driver.jog("arm", "cartesian", 0, 0, 1.0, "base")
    stop_ms = _time_to_standstill(watch, last) * 1000
    top = max(speeds)
    print(f"\nCartesian X jog at full slider: peak TCP speed {top * 1000:.1f} mm/s over {len(speeds)} samples; "
          f"travelled {(watch.getActualTCPPose()[0] - x0) * 1000:.0f} mm; standstill {stop_ms:.0f} ms after release")
    assert top <= 0.25, f"TCP at {top:.3f} m/s"
    assert top > 0.2, "the jog should reach close to the 0.25 m/s cap"
    # A joint jog of the base joint at full slider is capped at the TCP too (the TCP is ~0.5 m from its axis).
    speeds.clear()
    _jog_then(driver, watch, 0.8, ("arm", "joint", 0, 1, 1.0, "base"), sample)
    driver.jog("arm", "joint", 0, 0, 1.0, "base")
    print(f"base joint jog at full slider: peak TCP speed {max(speeds) * 1000:.1f} mm/s")
    assert max(speeds) <= 0.25
    wait_for(lambda: speed_of(watch) < 0.01, 2, what="standstill")


def test_stop_during_a_move_ends_it_with_stopped(cell) -> None:
    driver, watch = cell
    go_home(driver)
    result: dict = {}
    mover = threading.Thread(target=lambda: result.setdefault("r", driver.move_named("arm", "pick_approach", 0.5, 1.0)))
    mover.start()
    wait_for(lambda: speed_of(watch) > 0.3, 5, interval=0.005, what="the arm moving")
    t0 = time.monotonic()
    assert driver.stop() == (True, "stopped")
    stopped_after = _time_to_standstill(watch, t0)
    mover.join(5)
    assert result["r"] == (False, "stopped")
    assert stopped_after < 0.3
    assert np.max(np.abs(q_of(watch) - CONFIGS["pick_approach"])) > 0.05  # it stopped on the way
    assert driver.state().motion == "idle"


def test_gripper_tool_actions(cell) -> None:
    driver, watch = cell
    assert driver.tool_action("gripper", "close") == (True, "gripper close done")
    assert watch.getDigitalOutState(0) and watch.getActualDigitalInputBits() & 2
    assert driver.tool_action("gripper", "open") == (True, "gripper open done")
    assert not watch.getDigitalOutState(0) and not watch.getActualDigitalInputBits() & 2


def test_stop_also_halts_motion_another_client_started(cell) -> None:
    """/cell/manual/stop is the app's "Stop robot": it stops the arm whoever moves it."""
    import rtde_control
    driver, watch = cell
    other = rtde_control.RTDEControlInterface(HOST)  # another program takes the controller over
    try:
        q0 = q_of(watch)
        assert other.moveJ(list(q0 + [1.0, 0, 0, 0, 0, 0]), 0.5, 1.0, True)
        wait_for(lambda: speed_of(watch) > 0.3, 5, interval=0.005, what="the other program moving the arm")
        wait_for(lambda: not driver.snapshot().standstill(), 1, interval=0.005, what="the driver seeing it")
        t0 = time.monotonic()
        assert driver.stop() == (True, "stopped")
        stopped_after = _time_to_standstill(watch, t0)
        print(f"\nStop robot on another program's move: standstill after {stopped_after * 1000:.0f} ms")
        assert stopped_after < 0.5
        assert abs(q_of(watch)[0] - q0[0]) < 0.9  # stopped on the way
    finally:
        other.disconnect()
    go_home(driver)  # the driver's own script comes back for its next command


def test_power_off_is_refused_and_power_on_works_again(cell) -> None:
    import dashboard_client
    driver, watch = cell
    db = dashboard_client.DashboardClient(HOST)
    db.connect()
    try:
        db.powerOff()
        wait_for(lambda: driver.state().robot_mode == "POWER_OFF", 3, what="POWER_OFF in the state")
        assert driver.move_named("arm", "home") == (False, "robot is not powered on (mode POWER_OFF)")
        db.powerOn()
        db.brakeRelease()
        wait_for(lambda: driver.state().robot_mode == "RUNNING", 5, what="RUNNING again")
    finally:
        db.disconnect()
    go_home(driver)  # the driver starts its control script again (power off ended it)


def test_reconnects_after_the_controller_restarts() -> None:
    sim = start_sim(RESTART_HOST, "--no-ros", "--no-cameras")
    driver = make_driver(RESTART_HOST)
    try:
        go_home(driver)
        sim.stop()
        t0 = time.monotonic()
        wait_for(lambda: not driver.state().connected, 3, interval=0.01, what="the loss noticed")
        print(f"\ncontroller loss noticed after {(time.monotonic() - t0) * 1000:.0f} ms")
        assert driver.state().message == f"robot controller at {RESTART_HOST} is unreachable"
        assert driver.move_named("arm", "pick_approach") == (False, f"robot controller at {RESTART_HOST} is unreachable")
        sim = start_sim(RESTART_HOST, "--no-ros", "--no-cameras")
        t0 = time.monotonic()
        wait_for(lambda: driver.state().connected, 10, interval=0.02, what="reconnected")
        print(f"reconnected {(time.monotonic() - t0) * 1000:.0f} ms after the controller was back")
        assert driver.state().message == f"reconnected to the robot controller at {RESTART_HOST}"
        ok, why = driver.move_named("arm", "pick_approach", 1.0, 1.5)
        assert (ok, why) == (True, "arrived at pick_approach")
    finally:
        driver.shutdown()
        sim.stop()


# Freeze a process (SIGSTOP) for some seconds, then let it go on, as a controller whose data pauses. The test stops
# it at once (a helper's own start took long enough on CI for the move to arrive first); a helper continues it, since
# a ur_rtde call that blocks may hold this process's GIL past the pause.
THAW = "import os, signal, sys, time; time.sleep(float(sys.argv[2])); os.kill(int(sys.argv[1]), signal.SIGCONT)"


def ur_children(host: str) -> list[int]:
    """The pids of this process's ur_rtde children (ur_process) for a controller, alive."""
    found = []
    for pid in os.listdir("/proc"):
        try:
            stat = Path(f"/proc/{pid}/stat").read_text()
            cmd = Path(f"/proc/{pid}/cmdline").read_bytes()
        except (OSError, ValueError):
            continue
        fields = stat[stat.rindex(")") + 2:].split()
        if fields[0] != "Z" and int(fields[1]) == os.getpid() and b"cell_nodes.manual.ur_process" in cmd \
                and host.encode() in cmd.split(b"\0"):
            found.append(int(pid))
    return found


def test_a_controller_silent_mid_move_is_a_lost_connection_never_a_crash() -> None:
    """CI: the node died with SIGSEGV when the sim's data paused mid-move. ur_rtde closes a stream silent for 2.5 s,
    its control client reconnects on its own thread, and that raced the driver's call. Its clients now live in a
    child process each: the move fails, the driver reconnects, and the lost connection's children are gone (the old
    control client no longer fights the new one for the controller)."""
    sim = start_sim(FREEZE_HOST, "--no-ros", "--no-cameras")
    driver = make_driver(FREEZE_HOST)
    try:
        for target in ("pick_approach", "home", "pick_approach"):
            result: list[tuple[bool, str]] = []
            move = threading.Thread(target=lambda: result.append(driver.move_named("arm", target, 0.3, 0.5)))
            move.start()
            wait_for(lambda: driver.state().motion != "idle", 10, interval=0.01, what="the move started")
            os.kill(sim.proc.pid, signal.SIGSTOP)
            subprocess.run([sys.executable, "-c", THAW, str(sim.proc.pid), "3"], check=True, timeout=10)
            move.join(20)
            assert result == [(False, f"robot controller at {FREEZE_HOST} is unreachable")]
            wait_for(lambda: driver.state().connected, 20, interval=0.02, what="reconnected")
            # The lost connection's children are gone: the new connection's receive and IO clients are left.
            wait_for(lambda: len(ur_children(FREEZE_HOST)) == 2, 10, what="two ur_rtde children left")
        ok, why = driver.move_named("arm", "home", 1.0, 1.5)
        assert (ok, why) == (True, "arrived at home")
    finally:
        os.kill(sim.proc.pid, signal.SIGCONT)  # a failure while frozen must not leave the sim stopped
        driver.shutdown()
        sim.stop()
    wait_for(lambda: not ur_children(FREEZE_HOST), 10, what="no ur_rtde child after shutdown")


def test_the_node_keeps_reading_the_arm_while_a_slow_controller_starts_the_control_script() -> None:
    """ur_rtde's control client, made the usual way, holds the GIL until its script runs: the whole node froze for
    that long (5.5 s seen on a loaded host), no poll and no jog watchdog ran, and the frozen poll counted the controller
    as lost. The driver starts the script itself and waits for it without holding anything."""
    sim = start_sim(SLOW_HOST, "--no-ros", "--no-cameras", "--program-start", "3")
    driver = make_driver(SLOW_HOST)
    samples: list[float] = []
    driver.on_sample = lambda snap: samples.append(time.monotonic())
    try:
        t0 = time.monotonic()
        ok, why = driver.move_named("arm", "pick_approach", 1.0, 1.5)
        assert (ok, why) == (True, "arrived at pick_approach")
        took = time.monotonic() - t0
        assert took > 3.0, f"the move took {took:.2f} s: the sim did not make the script start slowly"
        gaps = np.diff([t for t in samples if t >= t0])
        assert gaps.max() < 0.5, f"the driver stopped reading the arm for {gaps.max():.2f} s while the script started"
        assert driver.state().connected
    finally:
        driver.shutdown()
        sim.stop()
