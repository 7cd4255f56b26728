"""Fixed-rate loops that neither drift nor burst after a stall."""
from __future__ import annotations

import threading
import time


class Pacer:
    def __init__(self, period: float, stop: threading.Event) -> None:
        self.period = period
        self.stop = stop
        self.next_t = time.perf_counter()

    def wait(self) -> None:
        """Sleep until the next tick (or until stopped). More than a period late: skip ahead instead of bursting."""
        self.next_t += self.period
        delay = self.next_t - time.perf_counter()
        if delay > 0:
            self.stop.wait(delay)
        elif delay < -self.period:
            self.next_t = time.perf_counter()
