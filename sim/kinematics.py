"""UR5 kinematics from the published DH parameters: the single source for the URDF, FK, IK and poses.

Poses are UR "p[x, y, z, rx, ry, rz]" vectors: position in metres and a rotation vector (axis * angle),
expressed in the robot base frame (DH frame 0), exactly what a UR controller reports as actual_TCP_pose.
"""
from __future__ import annotations

import math
from typing import Optional, Sequence

import numpy as np

# Published UR5 (CB3 / e-Series UR5 kinematics share these) standard DH parameters.
D = (0.089159, 0.0, 0.0, 0.10915, 0.09465, 0.0823)
A = (0.0, -0.425, -0.39225, 0.0, 0.0, 0.0)
ALPHA = (math.pi / 2, 0.0, 0.0, math.pi / 2, -math.pi / 2, 0.0)

JOINT_LIMIT = 2 * math.pi  # UR joints turn +-360 degrees


def dh_matrix(theta: float, d: float, a: float, alpha: float) -> np.ndarray:
    ct, st, ca, sa = math.cos(theta), math.sin(theta), math.cos(alpha), math.sin(alpha)
    return np.array([[ct, -st * ca, st * sa, a * ct],
                     [st, ct * ca, -ct * sa, a * st],
                     [0.0, sa, ca, d],
                     [0.0, 0.0, 0.0, 1.0]])


def fk_frames(q: Sequence[float]) -> list[np.ndarray]:
    """Base-to-frame transforms T_0^i for i = 0..6 (frame 6 = tool flange)."""
    frames = [np.eye(4)]
    for i in range(6):
        frames.append(frames[-1] @ dh_matrix(q[i], D[i], A[i], ALPHA[i]))
    return frames


def rotvec_to_matrix(r: Sequence[float]) -> np.ndarray:
    r = np.asarray(r, dtype=float)
    angle = float(np.linalg.norm(r))
    if angle < 1e-12:
        return np.eye(3)
    k = r / angle
    kx = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + math.sin(angle) * kx + (1 - math.cos(angle)) * (kx @ kx)


def matrix_to_rotvec(m: np.ndarray) -> np.ndarray:
    # Via a unit quaternion: numerically stable also near angle = pi.
    q = matrix_to_quat(m)
    return quat_to_rotvec(q)


def matrix_to_quat(m: np.ndarray) -> np.ndarray:
    """Rotation matrix -> quaternion (x, y, z, w), w >= 0."""
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
    q = np.array([x, y, z, w])
    q /= np.linalg.norm(q)
    return q if q[3] >= 0 else -q


def quat_to_rotvec(q: Sequence[float]) -> np.ndarray:
    x, y, z, w = q
    if w < 0:
        x, y, z, w = -x, -y, -z, -w
    s = math.sqrt(x * x + y * y + z * z)
    if s < 1e-12:
        return np.zeros(3)
    angle = 2 * math.atan2(s, w)
    return np.array([x, y, z]) / s * angle


def quat_to_matrix(q: Sequence[float]) -> np.ndarray:
    return rotvec_to_matrix(quat_to_rotvec(q))


def pose_to_matrix(pose: Sequence[float]) -> np.ndarray:
    t = np.eye(4)
    t[:3, :3] = rotvec_to_matrix(pose[3:6])
    t[:3, 3] = pose[0:3]
    return t


def matrix_to_pose(t: np.ndarray) -> np.ndarray:
    return np.concatenate([t[:3, 3], matrix_to_rotvec(t[:3, :3])])


def forward(q: Sequence[float], tcp: Sequence[float] = (0, 0, 0, 0, 0, 0)) -> np.ndarray:
    """UR forward kinematics: TCP pose p[x,y,z,rx,ry,rz] in the base frame."""
    return matrix_to_pose(fk_frames(q)[6] @ pose_to_matrix(tcp))


def jacobian(q: Sequence[float], tcp: Sequence[float] = (0, 0, 0, 0, 0, 0),
             frames: Optional[list[np.ndarray]] = None) -> np.ndarray:
    """Geometric Jacobian (linear; angular) of the TCP in the base frame."""
    frames = frames if frames is not None else fk_frames(q)
    p_end = (frames[6] @ pose_to_matrix(tcp))[:3, 3]
    j = np.empty((6, 6))
    for i in range(6):
        z = frames[i][:3, 2]
        r = p_end - frames[i][:3, 3]
        # explicit cross product: np.cross costs ~10x more for 3-vectors
        j[0, i] = z[1] * r[2] - z[2] * r[1]
        j[1, i] = z[2] * r[0] - z[0] * r[2]
        j[2, i] = z[0] * r[1] - z[1] * r[0]
        j[3:, i] = z
    return j


def pose_error(target: np.ndarray, current: np.ndarray) -> np.ndarray:
    """6-vector (position error, orientation error as rotation vector) between two 4x4 transforms."""
    dp = target[:3, 3] - current[:3, 3]
    dr = matrix_to_rotvec(target[:3, :3] @ current[:3, :3].T)
    return np.concatenate([dp, dr])


def inverse(pose: Sequence[float], q_near: Sequence[float], tcp: Sequence[float] = (0, 0, 0, 0, 0, 0),
            max_pos_err: float = 1e-10, max_ori_err: float = 1e-10, iterations: int = 200) -> Optional[np.ndarray]:
    """Numerical IK (damped least squares) from q_near: returns the solution nearest the seed, or None.

    Why numerical: a motion controller wants the solution continuous with the current configuration,
    which a seeded Newton iteration gives directly (the analytic 8 solutions would need picking).
    """
    target = pose_to_matrix(pose)
    tcp_t = pose_to_matrix(tcp)
    pos_tol = max(max_pos_err, 1e-9)
    ori_tol = max(max_ori_err, 1e-9)
    near = np.asarray(q_near, dtype=float)
    for seed in _seeds(near):
        q = seed.copy()
        lam = 1e-6
        frames = fk_frames(q)
        err = pose_error(target, frames[6] @ tcp_t)
        cost = float(err @ err)
        for _ in range(iterations):
            if np.linalg.norm(err[:3]) < pos_tol and np.linalg.norm(err[3:]) < ori_tol:
                return _wrap_near(q, near)
            j = jacobian(q, tcp, frames)
            dq = j.T @ np.linalg.solve(j @ j.T + lam * np.eye(6), err)
            step = float(np.max(np.abs(dq)))
            if step > 0.5:  # keep Newton steps small far from the solution
                dq *= 0.5 / step
            q_new = q + dq
            frames_new = fk_frames(q_new)
            err_new = pose_error(target, frames_new[6] @ tcp_t)
            cost_new = float(err_new @ err_new)
            # Levenberg-Marquardt: trust the Gauss-Newton step more while it helps, damp it when it does not.
            if cost_new < cost:
                q, err, cost, frames = q_new, err_new, cost_new, frames_new
                lam = max(lam * 0.3, 1e-9)
            else:
                lam = min(lam * 10, 1.0)
        if np.linalg.norm(err[:3]) < max(pos_tol, 1e-6) and np.linalg.norm(err[3:]) < max(ori_tol, 1e-6):
            return _wrap_near(q, near)
    return None


def _seeds(near: np.ndarray):
    """The given seed first; deterministic perturbed seeds only if it fails (they cost time to make)."""
    yield near
    rng = np.random.default_rng(0)
    for _ in range(8):
        yield near + rng.uniform(-1.0, 1.0, 6)


def _wrap_near(q: np.ndarray, near: np.ndarray) -> np.ndarray:
    """Shift each joint by multiples of 2*pi to the value nearest the seed, within joint limits."""
    out = q.copy()
    for i in range(6):
        k = round((near[i] - out[i]) / (2 * math.pi))
        cand = out[i] + k * 2 * math.pi
        if abs(cand) <= JOINT_LIMIT:
            out[i] = cand
    return out


def interpolate_pose(start: np.ndarray, end: np.ndarray, s: float) -> np.ndarray:
    """Straight-line position and slerp orientation between two 4x4 transforms, s in [0, 1]."""
    t = np.eye(4)
    t[:3, 3] = start[:3, 3] + s * (end[:3, 3] - start[:3, 3])
    rel = matrix_to_rotvec(end[:3, :3] @ start[:3, :3].T)
    t[:3, :3] = rotvec_to_matrix(rel * s) @ start[:3, :3]
    return t
