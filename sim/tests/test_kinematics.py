"""The generated URDF reproduces the UR5 DH forward kinematics; IK inverts it; physics is deterministic."""
from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from sim import kinematics as kin
from sim.urdf import DEFAULT_TCP
from sim.world import World

joint = st.floats(min_value=-math.pi, max_value=math.pi, allow_nan=False)
q_vectors = st.lists(joint, min_size=6, max_size=6)


def dh_reference(q) -> np.ndarray:
    """Textbook DH chain, written out independently of sim.kinematics."""
    d = [0.089159, 0, 0, 0.10915, 0.09465, 0.0823]
    a = [0, -0.425, -0.39225, 0, 0, 0]
    alpha = [math.pi / 2, 0, 0, math.pi / 2, -math.pi / 2, 0]
    t = np.eye(4)
    for i in range(6):
        ct, st_, ca, sa = math.cos(q[i]), math.sin(q[i]), math.cos(alpha[i]), math.sin(alpha[i])
        t = t @ np.array([[ct, -st_ * ca, st_ * sa, a[i] * ct], [st_, ct * ca, -ct * sa, a[i] * st_],
                          [0, sa, ca, d[i]], [0, 0, 0, 1]])
    return t


@pytest.fixture(scope="module")
def world():
    w = World(seed=0)
    yield w
    w.close()


@settings(max_examples=60, deadline=None)
@given(q=q_vectors)
def test_urdf_flange_matches_dh(world, q):
    p = world.p
    for j, v in zip(world.arm_joints, q):
        p.resetJointState(world.robot, j, v)
    flange_link = world.ft_joint - 1  # the fixed 'flange' link precedes the F/T sensor joint
    pos, orn = p.getLinkState(world.robot, flange_link, computeForwardKinematics=True)[4:6]
    ref = dh_reference(q)
    np.testing.assert_allclose(pos, ref[:3, 3], atol=1e-6)
    np.testing.assert_allclose(kin.quat_to_matrix(orn), ref[:3, :3], atol=1e-6)
    np.testing.assert_allclose(kin.fk_frames(q)[6], ref, atol=1e-12)


# Elbow and wrist angles drawn away from their singularities (|sin| > 0.2) by construction, so Hypothesis
# does not have to discard most examples.
away_from_singular = st.builds(lambda a, flip, turn: (a + math.pi * flip) * (1 if turn else -1),
                               st.floats(0.21, math.pi - 0.21), st.integers(0, 1), st.booleans())


@settings(max_examples=40, deadline=None)
@given(q=st.tuples(joint, joint, away_from_singular, joint, away_from_singular, joint).map(list),
       noise=st.lists(st.floats(-0.2, 0.2), min_size=6, max_size=6))
def test_inverse_kinematics_round_trip(q, noise):
    # Also away from the shoulder singularity (there the solution is not locally unique).
    assert abs(math.sin(q[2])) > 0.2 and abs(math.sin(q[4])) > 0.2
    wrist = kin.fk_frames(q)[5][:3, 3]
    assume(math.hypot(wrist[0], wrist[1]) > kin.D[3] + 0.05)
    pose = kin.forward(q, DEFAULT_TCP)
    sol = kin.inverse(pose, np.array(q) + np.array(noise), DEFAULT_TCP)
    assert sol is not None
    np.testing.assert_allclose(kin.forward(sol, DEFAULT_TCP)[:3], pose[:3], atol=1e-7)
    err = kin.matrix_to_rotvec(kin.rotvec_to_matrix(kin.forward(sol, DEFAULT_TCP)[3:]) @
                               kin.rotvec_to_matrix(pose[3:]).T)
    assert np.linalg.norm(err) < 1e-7


def test_rotation_vector_conversions_near_pi():
    for rv in ([math.pi - 1e-9, 0, 0], [0, 2.2214415, 2.2214415], [0.3, -0.2, 0.1]):
        m = kin.rotvec_to_matrix(rv)
        np.testing.assert_allclose(kin.rotvec_to_matrix(kin.matrix_to_rotvec(m)), m, atol=1e-8)


def _run(seed: int, steps: int = 400) -> tuple[np.ndarray, list]:
    from sim.controller import Controller
    from sim import motion
    w = World(seed=seed)
    c = Controller(w)
    c.arm.start(motion.JointMove(c.arm.q_set, c.arm.q_set + np.array([0.3, -0.2, 0.2, 0, 0.1, 0]), 1.0, 2.0))
    c.std_do = 1  # close the gripper on the way
    for _ in range(steps):
        c.tick()
    out = (w.arm_state().q, w.body_poses())
    w.close()
    return out


def test_physics_is_deterministic_for_a_seed():
    q1, b1 = _run(3)
    q2, b2 = _run(3)
    q3, b3 = _run(4)
    assert np.array_equal(q1, q2)
    assert b1 == b2
    assert b1 != b3, "another seed must place the parts differently"
