"""Two emulated controllers on different loopback addresses, driven at the same time."""
from __future__ import annotations

import threading

import numpy as np
import rtde_control
import rtde_receive


def test_two_emulators_run_side_by_side(start_sim):
    hosts = ("127.0.0.2", "127.0.0.3")
    for h in hosts:
        start_sim(h, "--speed", "2", "--no-cameras", "--no-ros")
    clients = {h: (rtde_control.RTDEControlInterface(h), rtde_receive.RTDEReceiveInterface(h)) for h in hosts}
    try:
        starts = {h: np.array(r.getActualQ()) for h, (_, r) in clients.items()}
        targets = {"127.0.0.2": starts["127.0.0.2"] + [0.4, 0, 0, 0, 0, 0],
                   "127.0.0.3": starts["127.0.0.3"] + [0, 0, 0, 0, 0, -0.6]}
        results: dict[str, bool] = {}
        threads = [threading.Thread(target=lambda h=h: results.__setitem__(
            h, clients[h][0].moveJ(list(targets[h]), 1.0, 2.0))) for h in hosts]
        for t in threads:
            t.start()
        for t in threads:
            t.join(30)
        assert results == {h: True for h in hosts}
        for h, (_, r) in clients.items():
            q = np.array(r.getActualQ())
            assert np.max(np.abs(q - targets[h])) < 1e-3, f"{h} did not reach its own target"
    finally:
        for c, r in clients.values():
            c.stopScript()
            c.disconnect()
            r.disconnect()
