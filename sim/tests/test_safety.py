"""The cell's force guard: driving the gripper into the table ends in a protective stop, reported like a UR."""
from __future__ import annotations

import time

import dashboard_client
import numpy as np
import rtde_control
import rtde_receive

from conftest import wait_for

HOST = "127.0.0.18"


def test_collision_with_table_trips_protective_stop(start_sim):
    start_sim(HOST, "--speed", "2", "--no-cameras", "--no-ros")
    r = rtde_receive.RTDEReceiveInterface(HOST)
    c = rtde_control.RTDEControlInterface(HOST)
    db = dashboard_client.DashboardClient(HOST)
    db.connect()
    try:
        target = np.array(r.getActualTCPPose())
        target[2] = -0.05  # 5 cm below the table top
        assert not c.moveL(list(target), 0.1, 0.5), "a move ending in a collision must fail"
        wait_for(r.isProtectiveStopped, 2, what="protective stop")
        assert db.safetystatus() == "Safetystatus: PROTECTIVE_STOP"
        assert r.getRuntimeState() == 1
        wait_for(lambda: max(abs(v) for v in r.getActualQd()) < 1e-3, 3, what="arm at rest")
        z = r.getActualTCPPose()[2]
        assert 0.0 < z < 0.05, f"the arm should stop at the table, TCP z = {z:.3f}"
        time.sleep(0.3)
        assert np.linalg.norm(r.getActualTCPForce()[:3]) < 100.0, "the stopped arm must not keep pushing"
        assert abs(r.getActualTCPPose()[2] - z) < 1e-3
    finally:
        db.disconnect()
        c.disconnect()
        r.disconnect()
