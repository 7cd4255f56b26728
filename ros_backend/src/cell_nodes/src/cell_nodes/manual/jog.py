"""Hold-to-run jogging: the supervisor that decides what each JogCommand means and when a jog has timed out.

The page publishes the held jog every 50 ms and direction 0 on release. Rules (DESIGN "Motion safety"):
- a jog runs only while its heartbeats keep coming: none for `timeout` (0.2 s) -> stop;
- direction 0 -> stop now;
- a different jog replaces the running one at once (the controller gets the new speed; nothing is queued);
- the same jog again is only a heartbeat (no new command to the controller);
- a running jog stopped by a stop (the stop service: Stop robot, Stop move, a take-over), a refused command, or
  the controller (lost, or stopping the arm itself) stays stopped while its heartbeats go on: only a new press (its
  `press` number changes), a different jog, or the release and a new press move the arm again. Why: "Stop robot"
  from another session did not hold while the holder's thumb stayed down (the next heartbeat restarted the arm).
  The heartbeat timeout holds the press too, as a teach pendant's enabling switch does: heartbeats that come again
  after a stall (a frozen page, a stalled BFF or rosbridge) never restart the arm by themselves; the operator lets
  go and presses again.
- a press that was released never moves the arm again: a heartbeat of it that arrives after its release (delayed on
  the way) is held (press numbers are never reused; press 0, a publisher without them, is not remembered).
The clock is injected so the timeout is tested without sleeping. Not thread-safe: the driver holds its lock.
"""
from __future__ import annotations

import enum
import math
import time
from dataclasses import dataclass
from typing import Callable, Optional

from ..said import Said, say

JOINT, CARTESIAN = "joint", "cartesian"
AXES = ("X", "Y", "Z", "RX", "RY", "RZ")
FRAMES = ("base", "tool")


@dataclass(frozen=True)
class Jog:
    group: str
    mode: str          # "joint" or "cartesian"
    axis: int          # joint: index into the group's joints; cartesian: 0..5 = X, Y, Z, RX, RY, RZ
    direction: int     # +1, -1; 0 = stop
    speed: float       # fraction (0, 1] of the manual maximum
    frame: str = "base"
    press: int = 0     # the page's number for this press of the button (0: a publisher without one)

    def label(self) -> Said:
        """What the state's motion_target says: "joint 2 +", "X -", "RZ + (tool)" (said with a code: the messages
        that name the jog say it in the user's language)."""
        sign = "+" if self.direction > 0 else "-"
        if self.mode == JOINT:
            return say("manual.jog_joint", "joint {joint} {sign}", joint=self.axis + 1, sign=sign)
        name = AXES[self.axis] if 0 <= self.axis < len(AXES) else str(self.axis)
        if self.frame == "tool":
            return say("manual.jog_axis_tool", "{axis} {sign} (tool)", axis=name, sign=sign)
        return say("manual.jog_axis", "{axis} {sign}", axis=name, sign=sign)

    def same_motion(self, other: Optional["Jog"]) -> bool:
        return other is not None and (self.group, self.mode, self.axis, self.direction, self.frame, self.press) == \
            (other.group, other.mode, other.axis, other.direction, other.frame, other.press) and \
            math.isclose(self.speed, other.speed, rel_tol=0, abs_tol=1e-9)


class Decision(enum.Enum):
    START = "start"            # send this jog's speed to the controller (new, or replacing another)
    HEARTBEAT = "heartbeat"    # the running jog continues; nothing to send
    STOP = "stop"              # stop the running jog now
    NOTHING = "nothing"        # a stop with no jog running
    HELD = "held"              # a heartbeat of a jog that was stopped: it stays stopped until a new press


class JogSupervisor:
    def __init__(self, timeout: float = 0.2, clock: Callable[[], float] = time.monotonic) -> None:
        self.timeout = timeout
        self.clock = clock
        self.active: Optional[Jog] = None
        self.stopped: Optional[Jog] = None   # a jog held stopped (see the rules): its heartbeats do nothing
        self.pressed: Optional[Jog] = None   # the last jog started and not released (held by a stop even when the
                                             # heartbeat timeout had already stopped it)
        self.last_beat = 0.0
        # The last press released, per group: a heartbeat of it that comes after its release (a message the link
        # delayed) must not start the arm again. Press numbers are never reused (0: a publisher without them).
        self.ended: dict[str, int] = {}

    def command(self, jog: Jog) -> Decision:
        if jog.direction == 0:  # released: the next press starts
            if jog.press:
                self.ended[jog.group] = jog.press
            return Decision.STOP if self.clear(released=True) is not None else Decision.NOTHING
        if jog.press and self.ended.get(jog.group) == jog.press:
            return Decision.HELD
        now = self.clock()
        if jog.same_motion(self.active):
            self.last_beat = now
            return Decision.HEARTBEAT
        if jog.same_motion(self.stopped):
            return Decision.HELD
        self.active, self.pressed, self.stopped, self.last_beat = jog, jog, None, now
        return Decision.START

    def started(self) -> None:
        """The controller took the running jog: its dead-man time counts from now. Heartbeats that came while the
        start was under way waited behind it (a slow controller or a loaded host); they must not count as missed."""
        if self.active is not None:
            self.last_beat = self.clock()

    def expired(self) -> bool:
        """True when the running jog missed its heartbeats for longer than the timeout."""
        return self.active is not None and self.clock() - self.last_beat > self.timeout

    def clear(self, hold: bool = True, released: bool = False) -> Optional[Jog]:
        """Forget the running jog (the caller stops the arm); returns it, or None if none ran. hold: its press's
        further heartbeats are held (see the module's rules), also when the heartbeat timeout had already stopped it;
        hold=False (a start the controller refused: it never moved) holds nothing; released: the press ended."""
        jog, self.active = self.active, None
        if released:
            self.stopped = self.pressed = None
        elif not hold:
            self.stopped = None
        else:
            self.stopped = jog or self.pressed
        return jog
