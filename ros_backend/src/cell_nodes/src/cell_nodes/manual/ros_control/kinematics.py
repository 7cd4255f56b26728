"""Kinematics of one arm from its URDF (the robot_description parameter), with KDL (Debian's python3-pykdl).

The URDF's joints between base_link and tip_link become a KDL chain the way kdl_parser builds it: one segment per
joint, named after the child link, its origin (xyz, rpy) as the segment's tip frame and the joint axis turned into
the parent frame. Poses are [x, y, z, rx, ry, rz] (m, rotation vector) of tip_link in base_link, like UR's.

Not thread-safe by itself in KDL (the solvers keep scratch data), so every solver call here takes one lock: the
driver asks for FK from its monitor thread while a service thread plans a move.
"""
from __future__ import annotations

import math
import threading
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from typing import Iterator, Optional, Sequence

import numpy as np
import PyKDL as kdl

POSITION_TOLERANCE = 1e-5   # m: an IK solution must reproduce the pose this closely (checked by FK)
ORIENTATION_TOLERANCE = 1e-4  # rad
IK_RESTARTS = 12            # further seeds after the given one fails (half near it, half anywhere in the limits)
IK_EPS = 1e-8               # LMA's stop on its weighted error norm
IK_MAX_ITERATIONS = 300     # per seed; LMA converges in 5-30 from a nearby seed, unreachable poses use them all
# Damped least squares for velocity IK: damping fades in below this smallest singular value (Chiaverini), so the
# joint speeds stay bounded at a singularity while the twist is followed exactly away from one.
DLS_SIGMA = 0.04
DLS_LAMBDA = 0.04


_TRANSLATIONAL = (kdl.Joint.TransAxis, kdl.Joint.TransX, kdl.Joint.TransY, kdl.Joint.TransZ)


class KinematicsError(ValueError):
    """The robot description cannot give the requested chain; the message says why."""


@dataclass(frozen=True)
class _JointSpec:
    name: str
    kind: str                   # revolute, continuous, prismatic, fixed
    parent: str
    child: str
    origin: kdl.Frame
    axis: tuple[float, float, float]
    lower: float
    upper: float
    velocity: float


def _floats(text: Optional[str], default: tuple[float, ...], what: str) -> tuple[float, ...]:
    if text is None:
        return default
    try:
        values = tuple(float(v) for v in text.split())
    except ValueError:
        raise KinematicsError(f"{what}: not numbers: {text!r}") from None
    if len(values) != len(default):
        raise KinematicsError(f"{what}: expected {len(default)} numbers, got {text!r}")
    return values


def _limit(el: Optional[ET.Element], attr: str, default: float, what: str) -> float:
    if el is None or el.get(attr) is None:
        return default
    try:
        return float(el.get(attr))  # type: ignore[arg-type]
    except ValueError:
        raise KinematicsError(f"{what}: limit {attr}={el.get(attr)!r} is not a number") from None


def _parse_joint(el: ET.Element) -> _JointSpec:
    name = el.get("name") or "?"
    kind = el.get("type") or ""
    what = f"joint {name!r}"
    parent, child = el.find("parent"), el.find("child")
    if parent is None or child is None or not parent.get("link") or not child.get("link"):
        raise KinematicsError(f"{what}: needs <parent link=...> and <child link=...>")
    org = el.find("origin")
    xyz = _floats(org.get("xyz") if org is not None else None, (0.0, 0.0, 0.0), f"{what} origin xyz")
    rpy = _floats(org.get("rpy") if org is not None else None, (0.0, 0.0, 0.0), f"{what} origin rpy")
    ax = el.find("axis")
    axis = _floats(ax.get("xyz") if ax is not None else None, (1.0, 0.0, 0.0), f"{what} axis")
    norm = math.sqrt(sum(a * a for a in axis))
    if kind in ("revolute", "continuous", "prismatic") and norm < 1e-12:
        raise KinematicsError(f"{what}: zero axis")
    axis = tuple(a / norm for a in axis) if norm > 0 else axis
    lim = el.find("limit")
    lower, upper = -math.inf, math.inf
    if kind in ("revolute", "prismatic"):
        lower = _limit(lim, "lower", -math.inf, what)
        upper = _limit(lim, "upper", math.inf, what)
        # Soft limits (safety_controller) are what a ros_control driver enforces when the URDF has them.
        soft = el.find("safety_controller")
        if soft is not None:
            lower = max(lower, _limit(soft, "soft_lower_limit", -math.inf, what))
            upper = min(upper, _limit(soft, "soft_upper_limit", math.inf, what))
        if lower > upper:
            raise KinematicsError(f"{what}: lower limit {lower:g} above upper limit {upper:g}")
    velocity = _limit(lim, "velocity", math.inf, what)
    if not velocity > 0:   # 0 or missing in a sloppy URDF: no limit known (the caller's speed caps apply)
        velocity = math.inf
    origin = kdl.Frame(kdl.Rotation.RPY(*rpy), kdl.Vector(*xyz))
    return _JointSpec(name, kind, parent.get("link"), child.get("link"), origin, axis,  # type: ignore[arg-type]
                      lower, upper, velocity)


def _segment(spec: _JointSpec) -> kdl.Segment:
    """As kdl_parser: the joint sits at the origin, its axis expressed in the parent link's frame."""
    if spec.kind == "fixed":
        joint = kdl.Joint(spec.name, kdl.Joint.Fixed)
    else:
        jtype = kdl.Joint.TransAxis if spec.kind == "prismatic" else kdl.Joint.RotAxis
        joint = kdl.Joint(spec.name, spec.origin.p, spec.origin.M * kdl.Vector(*spec.axis), jtype)
    return kdl.Segment(spec.child, joint, spec.origin)


def _frame(pose: Sequence[float]) -> kdl.Frame:
    if len(pose) != 6 or not all(math.isfinite(float(v)) for v in pose):
        raise ValueError(f"a pose is 6 finite numbers [x, y, z, rx, ry, rz], got {list(pose)!r}")
    rx, ry, rz = float(pose[3]), float(pose[4]), float(pose[5])
    angle = math.sqrt(rx * rx + ry * ry + rz * rz)
    rot = kdl.Rotation.Rot(kdl.Vector(rx / angle, ry / angle, rz / angle), angle) if angle > 1e-12 \
        else kdl.Rotation.Identity()
    return kdl.Frame(rot, kdl.Vector(float(pose[0]), float(pose[1]), float(pose[2])))


def _pose(f: kdl.Frame) -> list[float]:
    """Rotation vector via the unit quaternion (w >= 0, angle in [0, pi]): same convention as frames.py."""
    x, y, z, w = f.M.GetQuaternion()
    if w < 0:
        x, y, z, w = -x, -y, -z, -w
    s = math.sqrt(x * x + y * y + z * z)
    k = 2 * math.atan2(s, w) / s if s > 1e-12 else 2.0
    p = f.p
    return [p[0], p[1], p[2], x * k, y * k, z * k]


class Kinematics:
    """FK, IK, Jacobian and velocity IK of the chain base_link -> tip_link (movable joints only, base to tip)."""

    def __init__(self, chain: kdl.Chain, joint_names: Sequence[str], lower: Sequence[float],
                 upper: Sequence[float], velocity_limits: Sequence[float], continuous: Sequence[bool],
                 base_link: str = "", tip_link: str = "") -> None:
        n = chain.getNrOfJoints()
        if not (len(joint_names) == len(lower) == len(upper) == len(velocity_limits) == len(continuous) == n):
            raise KinematicsError(f"the chain has {n} joints but {len(joint_names)} names/limits were given")
        self.chain = chain
        self.joint_names = list(joint_names)
        self.lower = [float(v) for v in lower]
        self.upper = [float(v) for v in upper]
        self.velocity_limits = [float(v) for v in velocity_limits]
        self.continuous = [bool(c) for c in continuous]
        self.base_link, self.tip_link = base_link, tip_link
        self.n = n
        self._lock = threading.Lock()
        self._fk = kdl.ChainFkSolverPos_recursive(chain)
        self._jac = kdl.ChainJntToJacSolver(chain)
        # The constructor taking per-axis error weights (L) segfaults in Debian's PyKDL 1.5.1: KDL's default
        # weights with a tight eps instead; the FK check against both tolerances decides anyway.
        self._ik = kdl.ChainIkSolverPos_LMA(chain, IK_EPS, IK_MAX_ITERATIONS, 1e-15)
        self._q = kdl.JntArray(n)
        self._q_out = kdl.JntArray(n)
        self._j = kdl.Jacobian(n)
        self._out = kdl.Frame()
        self._prismatic = [self.chain.getSegment(k).getJoint().getType() in _TRANSLATIONAL
                           for k in range(self.chain.getNrOfSegments())
                           if self.chain.getSegment(k).getJoint().getType() != kdl.Joint.Fixed]

    # ---- construction ----------------------------------------------------------------------------------------
    @classmethod
    def from_urdf(cls, xml: str, base_link: str, tip_link: str) -> "Kinematics":
        try:
            root = ET.fromstring(xml)
        except (ET.ParseError, TypeError, ValueError) as e:
            raise KinematicsError(f"the robot description is not valid XML: {e}") from None
        if root.tag != "robot":
            raise KinematicsError(f"the robot description is not a URDF (root element <{root.tag}>, not <robot>)")
        links = {el.get("name") for el in root.findall("link")}
        joints = [_parse_joint(el) for el in root.findall("joint")]
        links |= {j.child for j in joints} | {j.parent for j in joints}
        for role, name in (("base link", base_link), ("tip link", tip_link)):
            if name not in links:
                known = ", ".join(sorted(n for n in links if n)) or "none"
                raise KinematicsError(f"{role} {name!r} is not in the robot description (links: {known})")
        by_child = {j.child: j for j in joints}
        path: list[_JointSpec] = []
        link = tip_link
        while link != base_link:
            j = by_child.get(link)
            if j is None:
                raise KinematicsError(f"no kinematic chain from {base_link!r} to {tip_link!r}: "
                                      f"{tip_link!r} is not below {base_link!r} in the robot description")
            if len(path) > len(joints):
                raise KinematicsError("the robot description's joints form a loop")
            path.append(j)
            link = j.parent
        path.reverse()
        chain = kdl.Chain()
        names: list[str] = []
        lower: list[float] = []
        upper: list[float] = []
        vel: list[float] = []
        cont: list[bool] = []
        for j in path:
            if j.kind not in ("revolute", "continuous", "prismatic", "fixed"):
                raise KinematicsError(f"joint {j.name!r} of type {j.kind!r} is not supported in an arm chain "
                                      "(revolute, continuous, prismatic, fixed)")
            chain.addSegment(_segment(j))
            if j.kind != "fixed":
                names.append(j.name)
                lower.append(j.lower)
                upper.append(j.upper)
                vel.append(j.velocity)
                cont.append(j.kind == "continuous")
        if not names:
            raise KinematicsError(f"the chain from {base_link!r} to {tip_link!r} has no movable joint")
        return cls(chain, names, lower, upper, vel, cont, base_link, tip_link)

    # ---- helpers ---------------------------------------------------------------------------------------------
    def _load(self, q: Sequence[float]) -> kdl.JntArray:
        if len(q) != self.n:
            raise ValueError(f"expected {self.n} joint values ({', '.join(self.joint_names)}), got {len(q)}")
        arr = self._q
        for i, v in enumerate(q):
            arr[i] = v
        return arr

    def limit_violation(self, q: Sequence[float], margin: float = 0.0) -> Optional[int]:
        """Index of the first joint outside its position limits (by more than margin), or None."""
        for i, v in enumerate(q):
            if v < self.lower[i] - margin or v > self.upper[i] + margin:
                return i
        return None

    def within_limits(self, q: Sequence[float], margin: float = 1e-9) -> bool:
        return self.limit_violation(q, margin) is None

    # ---- position kinematics ---------------------------------------------------------------------------------
    def fk(self, q: Sequence[float]) -> list[float]:
        """Pose of tip_link in base_link: [x, y, z, rx, ry, rz]."""
        with self._lock:
            self._fk.JntToCart(self._load(q), self._out)
            return _pose(self._out)

    def fk_frame(self, q: Sequence[float]) -> kdl.Frame:
        with self._lock:
            out = kdl.Frame()
            self._fk.JntToCart(self._load(q), out)
            return out

    def pose_error(self, q: Sequence[float], pose: Sequence[float]) -> tuple[float, float]:
        """(position error m, orientation error rad) of FK(q) against pose."""
        tw = kdl.diff(self.fk_frame(q), _frame(pose))
        return tw.vel.Norm(), tw.rot.Norm()

    def ik(self, pose: Sequence[float], q_seed: Sequence[float], *, within_limits: bool = True,
           restarts: bool = True) -> Optional[list[float]]:
        """Joint values reaching `pose`, near q_seed; None when none is found.

        Tries q_seed first, then (restarts=True) perturbed and spread seeds; each result is verified by FK to
        POSITION_TOLERANCE / ORIENTATION_TOLERANCE. within_limits=True: moved by whole turns towards the seed where
        that helps, and refused when a joint stays outside its limits. within_limits=False, restarts=False: the
        plain continuation from the seed (linear moves use it to tell a limit crossing from an unreachable pose).
        """
        target = _frame(pose)
        seed0 = [float(v) for v in q_seed]
        if len(seed0) != self.n:
            raise ValueError(f"expected {self.n} joint values, got {len(seed0)}")
        for seed in self._seeds(seed0, restarts):
            q = self._solve(target, seed)
            if q is None:
                continue
            q = self._wrap(q, seed0, within_limits)
            if q is not None:
                return q
        return None

    def _solve(self, target: kdl.Frame, seed: Sequence[float]) -> Optional[list[float]]:
        with self._lock:
            self._ik.CartToJnt(self._load(seed), target, self._q_out)
            q = [self._q_out[i] for i in range(self.n)]
            self._fk.JntToCart(self._q_out, self._out)
            tw = kdl.diff(self._out, target)
        # Whatever the solver's status says, only an FK-verified result counts.
        if tw.vel.Norm() <= POSITION_TOLERANCE and tw.rot.Norm() <= ORIENTATION_TOLERANCE and \
                all(math.isfinite(v) for v in q):
            return q
        return None

    def _wrap(self, q: list[float], near: Sequence[float], within_limits: bool) -> Optional[list[float]]:
        """Each revolute joint by whole turns to the value nearest `near` (within its limits when asked; None when
        a joint has no such value)."""
        out = list(q)
        for i in range(self.n):
            if self._prismatic[i]:
                cands = [q[i]]
            else:
                base = q[i] + 2 * math.pi * round((near[i] - q[i]) / (2 * math.pi))
                if self.continuous[i] or not within_limits:
                    out[i] = base
                    continue
                cands = [base, base - 2 * math.pi, base + 2 * math.pi]
            if not within_limits:
                continue
            inside = [c for c in cands if self.lower[i] - 1e-9 <= c <= self.upper[i] + 1e-9]
            if not inside:
                return None
            best = min(inside, key=lambda c: abs(c - near[i]))
            out[i] = min(max(best, self.lower[i]), self.upper[i])
        return out

    def _seeds(self, seed: list[float], restarts: bool) -> Iterator[list[float]]:
        """The given seed, then deterministic ones: perturbed around it, then spread over the joint ranges."""
        yield seed
        if not restarts:
            return
        rng = np.random.default_rng(12345)
        lo = [v if math.isfinite(v) else -math.pi for v in self.lower]
        hi = [v if math.isfinite(v) else math.pi for v in self.upper]
        for k in range(IK_RESTARTS):
            if k < IK_RESTARTS // 2:
                s = [min(max(v + d, lo[i]), hi[i]) for i, (v, d) in enumerate(zip(seed, rng.uniform(-0.6, 0.6, self.n)))]
            else:
                s = [float(rng.uniform(lo[i], hi[i])) for i in range(self.n)]
            yield s

    # ---- velocity kinematics ---------------------------------------------------------------------------------
    def jacobian(self, q: Sequence[float]) -> np.ndarray:
        """6 x n geometric Jacobian at the tip, base axes: rows vx, vy, vz, wx, wy, wz."""
        with self._lock:
            self._jac.JntToJac(self._load(q), self._j)
            j = self._j
            return np.array([[j[r, c] for c in range(self.n)] for r in range(6)])

    def twist_to_joint_velocities(self, q: Sequence[float], twist: Sequence[float]) -> list[float]:
        """Joint velocities for a TCP twist (vx, vy, vz m/s, wx, wy, wz rad/s; base axes, about the TCP).

        Damped least squares: exact away from singularities; near one, the damping trades tracking for bounded
        joint speeds, and the resulting twist is never larger than the one asked for (each singular direction is
        scaled by s^2 / (s^2 + lambda^2) <= 1).
        """
        v = np.asarray(twist, dtype=float)
        if v.shape != (6,) or not np.all(np.isfinite(v)):
            raise ValueError(f"a twist is 6 finite numbers, got {list(twist)!r}")
        u, s, vt = np.linalg.svd(self.jacobian(q), full_matrices=False)
        smin = float(s[-1]) if len(s) >= 6 else 0.0
        lam2 = 0.0 if smin >= DLS_SIGMA else (1.0 - (smin / DLS_SIGMA) ** 2) * DLS_LAMBDA ** 2
        gains = np.where(s > 1e-12, s / (s * s + lam2) if lam2 > 0 else 1.0 / np.maximum(s, 1e-12), 0.0)
        qd = vt.T @ (gains * (u.T @ v))
        return [float(x) for x in qd]

    def tcp_velocity(self, q: Sequence[float], qd: Sequence[float]) -> list[float]:
        """The TCP twist (base axes) for joint velocities qd."""
        return [float(x) for x in self.jacobian(q) @ np.asarray(qd, dtype=float)]

    def tcp_speed(self, q: Sequence[float], qd: Sequence[float]) -> float:
        """Linear speed of the TCP (m/s) for joint velocities qd at q."""
        j = self.jacobian(q)
        return float(np.linalg.norm(j[:3] @ np.asarray(qd, dtype=float)))
