"""Dashboard server through ur_rtde's DashboardClient: power-up, brake release, protective stop unlock."""
from __future__ import annotations

import socket

import dashboard_client
import pytest
import rtde_control
import rtde_receive

from conftest import wait_for

HOST = "127.0.0.12"


@pytest.fixture
def cold_arm(start_sim):
    """A controller that boots like a real one: powered off, brakes on."""
    start_sim(HOST, "--speed", "4", "--no-cameras", "--no-ros", "--power-off")
    db = dashboard_client.DashboardClient(HOST)
    db.connect()
    r = rtde_receive.RTDEReceiveInterface(HOST)
    yield db, r
    r.disconnect()
    db.disconnect()


def test_power_brake_protective_stop_unlock_cycle(cold_arm):
    db, r = cold_arm
    assert db.robotmode() == "Robotmode: POWER_OFF"
    assert r.getRobotMode() == 3
    assert db.polyscopeVersion().startswith("5.")
    assert db.isInRemoteControl()
    assert db.getSerialNumber().isdigit()
    db.powerOn()
    wait_for(lambda: db.robotmode() == "Robotmode: IDLE", 5, what="IDLE after power on")
    wait_for(lambda: r.getRobotMode() == 5, 1, what="RTDE robot_mode IDLE")
    assert r.getRobotStatus() & 1  # power-on bit
    db.brakeRelease()
    wait_for(lambda: db.robotmode() == "Robotmode: RUNNING", 5, what="RUNNING after brake release")
    wait_for(lambda: r.getRobotMode() == 7, 2, what="RTDE robot_mode RUNNING")

    c = rtde_control.RTDEControlInterface(HOST)
    try:
        assert db.running()
        assert db.programState().startswith("PLAYING")
        assert c.triggerProtectiveStop() is not None
        wait_for(r.isProtectiveStopped, 3, what="protective stop reported")
        assert r.getSafetyMode() == 3                    # PROTECTIVE_STOP
        assert r.getSafetyStatusBits() & (1 << 2)        # is_protective_stopped
        assert db.safetystatus() == "Safetystatus: PROTECTIVE_STOP"
        assert not db.running(), "a protective stop stops the control script"
        assert not c.moveJ(r.getActualQ(), 1.0, 1.0)    # motion refused while stopped
        with pytest.raises(RuntimeError, match="Cannot unlock protective stop until 5s"):
            db.unlockProtectiveStop()                    # too early: refused like a real controller
        db.closeSafetyPopup()
        wait_for(lambda: _try_unlock(db), 5, interval=0.1, what="unlock after 5 s (sim time)")
        assert db.safetystatus() == "Safetystatus: NORMAL"
        wait_for(lambda: r.getSafetyMode() == 1, 2, what="RTDE safety mode NORMAL")
        assert c.reuploadScript()
        wait_for(c.isProgramRunning, 5, what="script running again")
        q = r.getActualQ()
        q[0] += 0.1
        assert c.moveJ(q, 1.0, 1.0)
    finally:
        c.stopScript()
        c.disconnect()
    db.powerOff()
    wait_for(lambda: r.getRobotMode() == 3, 2, what="POWER_OFF")


def _try_unlock(db) -> bool:
    try:
        db.unlockProtectiveStop()
        return True
    except RuntimeError:
        return False


def test_play_stop_pause_and_refusals(start_sim):
    start_sim(HOST, "--speed", "4", "--no-cameras", "--no-ros")
    with socket.create_connection((HOST, 29999), timeout=3) as s:
        f = s.makefile("rw", newline="\n")
        assert f.readline().strip() == "Connected: Universal Robots Dashboard Server"

        def ask(cmd: str) -> str:
            f.write(cmd + "\n")
            f.flush()
            return f.readline().strip()

        assert ask("play") == "Failed to execute: play"          # nothing loaded
        assert ask("load missing.txt") == "File not found: missing.txt"
        assert ask("load pick.urp") == "Loading program: /programs/pick.urp"
        assert ask("play") == "Starting program"
        wait_for(lambda: ask("programState") == "PLAYING pick.urp", 2, what="program playing")
        assert ask("pause") == "Pausing program"
        assert ask("programState") == "PAUSED pick.urp"
        assert ask("play") == "Starting program"
        assert ask("stop") == "Stopped"
        assert ask("running") == "Program running: false"
        assert ask("fly to the moon") == "could not understand: 'fly to the moon'"
        assert ask("get robot model") == "UR5"
        assert ask("robotmode") == "Robotmode: RUNNING"
        assert ask("quit") == "Disconnected"
