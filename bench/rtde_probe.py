"""The controller's own view of the arm, for bench/manual_bench.mjs: ur_rtde receive at 500 Hz.

Prints one line per sample: wall time (s), TCP linear speed (m/s), largest joint speed (rad/s).
"""
from __future__ import annotations

import math
import sys
import time

import rtde_receive


def main(host: str) -> None:
    rx = rtde_receive.RTDEReceiveInterface(host, 500.0)
    period = 0.002
    nxt = time.monotonic()
    while True:
        v = rx.getActualTCPSpeed()
        qd = rx.getActualQd()
        lin = math.sqrt(v[0] ** 2 + v[1] ** 2 + v[2] ** 2)
        sys.stdout.write(f"{time.time():.6f} {lin:.6f} {max(abs(x) for x in qd):.6f}\n")
        sys.stdout.flush()
        nxt += period
        time.sleep(max(0.0, nxt - time.monotonic()))


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "127.0.0.1")
