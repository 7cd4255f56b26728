"""Poses and frames for UR controllers: p[x, y, z, rx, ry, rz] in metres and a rotation vector (axis * angle, rad),
in the robot base frame, exactly what the controller reports as actual_TCP_pose.
"""
from __future__ import annotations

import math
from typing import Sequence

import numpy as np


def rotvec_to_matrix(r: Sequence[float]) -> np.ndarray:
    """Rodrigues' formula."""
    v = np.asarray(r, dtype=float)
    angle = float(np.linalg.norm(v))
    if angle < 1e-12:
        return np.eye(3)
    k = v / angle
    kx = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    return np.eye(3) + math.sin(angle) * kx + (1 - math.cos(angle)) * (kx @ kx)


def matrix_to_rotvec(m: np.ndarray) -> np.ndarray:
    """Via a unit quaternion: stable near a half turn too (where the axis comes from the diagonal)."""
    m = np.asarray(m, dtype=float)
    tr = m[0, 0] + m[1, 1] + m[2, 2]
    if tr > 0:
        s = math.sqrt(tr + 1.0) * 2
        w, x, y, z = 0.25 * s, (m[2, 1] - m[1, 2]) / s, (m[0, 2] - m[2, 0]) / s, (m[1, 0] - m[0, 1]) / s
    elif m[0, 0] > m[1, 1] and m[0, 0] > m[2, 2]:
        s = math.sqrt(1.0 + m[0, 0] - m[1, 1] - m[2, 2]) * 2
        w, x, y, z = (m[2, 1] - m[1, 2]) / s, 0.25 * s, (m[0, 1] + m[1, 0]) / s, (m[0, 2] + m[2, 0]) / s
    elif m[1, 1] > m[2, 2]:
        s = math.sqrt(1.0 + m[1, 1] - m[0, 0] - m[2, 2]) * 2
        w, x, y, z = (m[0, 2] - m[2, 0]) / s, (m[0, 1] + m[1, 0]) / s, 0.25 * s, (m[1, 2] + m[2, 1]) / s
    else:
        s = math.sqrt(1.0 + m[2, 2] - m[0, 0] - m[1, 1]) * 2
        w, x, y, z = (m[1, 0] - m[0, 1]) / s, (m[0, 2] + m[2, 0]) / s, (m[1, 2] + m[2, 1]) / s, 0.25 * s
    if w < 0:
        w, x, y, z = -w, -x, -y, -z
    n = math.sqrt(x * x + y * y + z * z)
    if n < 1e-12:
        return np.zeros(3)
    return np.array([x, y, z]) / n * (2 * math.atan2(n, w))


def pose_to_matrix(pose: Sequence[float]) -> np.ndarray:
    t = np.eye(4)
    t[:3, :3] = rotvec_to_matrix(pose[3:6])
    t[:3, 3] = pose[0:3]
    return t


def matrix_to_pose(t: np.ndarray) -> list[float]:
    return [float(v) for v in np.concatenate([t[:3, 3], matrix_to_rotvec(t[:3, :3])])]


def relative_target(current: Sequence[float], offset: Sequence[float], frame: str) -> list[float]:
    """The pose `offset` away from `current`.

    base: translate along the base axes; rotate about base-parallel axes through the TCP (the TCP stays put).
    tool: translate along the tool axes; rotate about the tool axes (current * offset).
    """
    cur = pose_to_matrix(current)
    off = pose_to_matrix(offset)
    if frame == "tool":
        return matrix_to_pose(cur @ off)
    if frame == "base":
        out = np.eye(4)
        out[:3, :3] = off[:3, :3] @ cur[:3, :3]
        out[:3, 3] = cur[:3, 3] + off[:3, 3]
        return matrix_to_pose(out)
    raise ValueError(f"unknown frame {frame!r} (base or tool)")


def tool_twist_to_base(twist: Sequence[float], tcp_pose: Sequence[float]) -> list[float]:
    """A TCP twist (v, w) given along the tool axes, expressed along the base axes (speedL takes base-frame speeds).
    For a one-axis jog this stays exact while the arm moves: translating does not turn the tool, and turning about
    a tool axis leaves that axis where it is."""
    r = rotvec_to_matrix(tcp_pose[3:6])
    tw = np.asarray(twist, dtype=float)
    return [float(v) for v in np.concatenate([r @ tw[:3], r @ tw[3:]])]


def pose_distance(a: Sequence[float], b: Sequence[float]) -> tuple[float, float]:
    """(position distance in m, rotation angle in rad) between two poses."""
    ma, mb = pose_to_matrix(a), pose_to_matrix(b)
    d = float(np.linalg.norm(ma[:3, 3] - mb[:3, 3]))
    ang = float(np.linalg.norm(matrix_to_rotvec(mb[:3, :3] @ ma[:3, :3].T)))
    return d, ang


def rotvec_to_quaternion(r: Sequence[float]) -> tuple[float, float, float, float]:
    """(x, y, z, w), as geometry_msgs/Quaternion wants it."""
    angle = math.sqrt(sum(v * v for v in r))
    if angle < 1e-12:
        return 0.0, 0.0, 0.0, 1.0
    s = math.sin(angle / 2) / angle
    return r[0] * s, r[1] * s, r[2] * s, math.cos(angle / 2)
