"""Speed and acceleration limits of manual motion: defaults, the cell file's maxima, and the hard TCP cap.

Units: rad/s and rad/s^2 for joint motion, m/s and m/s^2 for Cartesian motion (rotations in Cartesian jogs use
the joint figures, rad/s about the TCP). A request of 0 (or anything not a positive number) means "the default";
anything above a maximum is clamped to it, never refused, so the UI can offer fractions of the limits.
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Mapping, Optional

# ISO 10218-1 reduced speed for manual (hold-to-run) motion: the TCP never faster, whatever the cell file says.
TCP_SPEED_CAP = 0.25                # m/s
DEFAULT_TCP_SPEED = 0.1             # m/s, a Cartesian move with speed 0 (capped by max_tcp_speed)
DEFAULT_TCP_ACCELERATION = 0.5      # m/s^2 (capped by max_tcp_acceleration)
FALLBACK = {"default_speed": 0.25, "default_acceleration": 0.5, "max_speed": 1.0, "max_acceleration": 1.5,
            "max_tcp_speed": TCP_SPEED_CAP, "max_tcp_acceleration": 1.0}
# Commands stay this fraction under the TCP cap: the arm's tracking overshoots a commanded speed by a few tenths
# of a percent (250.5 mm/s measured for 250 commanded, sim), and the cap is on the actual speed.
TCP_COMMAND_MARGIN = 0.98
# Firm stops: release-to-standstill must stay under 300 ms (DESIGN "Motion safety"); 1 rad/s stops in 0.1 s.
STOP_DECEL_JOINT = 10.0             # rad/s^2 (speedStop after a joint jog, stopJ for joint moves)
STOP_DECEL_TCP = 5.0                # m/s^2 and rad/s^2 (speedStop after a Cartesian jog, stopL for linear moves)
# Heartbeats lost (frozen link, crashed page): stop harder, the 0.2 s timeout has already used most of the time.
WATCHDOG_DECEL_JOINT = 20.0         # rad/s^2
WATCHDOG_DECEL_TCP = 10.0           # m/s^2 and rad/s^2


def _positive(x: Optional[float]) -> bool:
    return x is not None and isinstance(x, (int, float)) and math.isfinite(x) and x > 0


@dataclass(frozen=True)
class Limits:
    default_speed: float            # rad/s
    default_acceleration: float     # rad/s^2
    max_speed: float                # rad/s
    max_acceleration: float         # rad/s^2
    max_tcp_speed: float            # m/s, <= TCP_SPEED_CAP
    max_tcp_acceleration: float     # m/s^2
    jog_timeout: float              # s

    @classmethod
    def from_section(cls, raw: Mapping[str, float], jog_timeout: float = 0.2) -> "Limits":
        v = {k: float(raw[k]) if _positive(raw.get(k)) else d for k, d in FALLBACK.items()}
        max_tcp = min(v["max_tcp_speed"], TCP_SPEED_CAP)
        return cls(default_speed=min(v["default_speed"], v["max_speed"]),
                   default_acceleration=min(v["default_acceleration"], v["max_acceleration"]),
                   max_speed=v["max_speed"], max_acceleration=v["max_acceleration"],
                   max_tcp_speed=max_tcp, max_tcp_acceleration=v["max_tcp_acceleration"],
                   jog_timeout=jog_timeout)

    def as_dict(self) -> dict[str, float]:
        return asdict(self)

    @property
    def tcp_command_cap(self) -> float:
        """The highest TCP speed ever commanded (m/s): max_tcp_speed less the tracking margin."""
        return self.max_tcp_speed * TCP_COMMAND_MARGIN

    # ---- service moves ------------------------------------------------------------------------
    def joint_speed(self, requested: float) -> float:
        return min(requested, self.max_speed) if _positive(requested) else self.default_speed

    def joint_acceleration(self, requested: float) -> float:
        return min(requested, self.max_acceleration) if _positive(requested) else self.default_acceleration

    def tcp_speed(self, requested: float) -> float:
        return min(requested if _positive(requested) else DEFAULT_TCP_SPEED, self.tcp_command_cap)

    def tcp_acceleration(self, requested: float) -> float:
        return min(requested if _positive(requested) else DEFAULT_TCP_ACCELERATION, self.max_tcp_acceleration)

    # ---- jogging --------------------------------------------------------------------------------
    @staticmethod
    def jog_fraction(fraction: float) -> Optional[float]:
        """The slider value clamped to (0, 1]; None when it is not a positive number (the jog is refused)."""
        return min(float(fraction), 1.0) if _positive(fraction) else None

    def joint_jog_speed(self, fraction: float, lever: Optional[float] = None) -> float:
        """rad/s for a one-joint jog. `lever`: metres of TCP travel per radian of that joint (its distance from the
        joint axis); a one-joint jog moves the TCP on a circle, so capping speed * lever keeps the TCP under
        max_tcp_speed for the whole jog (reduced speed applies to joint jogs too)."""
        speed = (self.jog_fraction(fraction) or 0.0) * self.max_speed
        if lever is not None and lever > 1e-6:
            speed = min(speed, self.tcp_command_cap / lever)
        return speed

    def cartesian_jog_speed(self, axis: int, fraction: float) -> float:
        """m/s along X/Y/Z (axis 0..2), rad/s about RX/RY/RZ (axis 3..5)."""
        f = self.jog_fraction(fraction) or 0.0
        return f * (self.tcp_command_cap if axis < 3 else self.max_speed)

    def cartesian_jog_acceleration(self, axis: int) -> float:
        return self.max_tcp_acceleration if axis < 3 else self.max_acceleration
