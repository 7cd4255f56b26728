"""The physical cell in PyBullet: UR5 + F/T sensor + gripper, table, graspable cubes, a fixture.

One World owns one PyBullet client (DIRECT, headless), so several cells live side by side in one process.
The same construction code builds the render-only replica used by the camera process.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Optional, Sequence

import numpy as np
import pybullet
from pybullet_utils import bullet_client

from . import urdf

PHYSICS_HZ = 500          # fixed physics step; also the controller tick (UR e-Series runs at 500 Hz)
DT = 1.0 / PHYSICS_HZ
HOME_Q = (0.0, -1.5708, 1.5708, -1.5708, -1.5708, 0.0)
ARM_FORCES = (330.0, 330.0, 150.0, 56.0, 56.0, 56.0)   # max joint torques (N m), UR5 sizes 3/3/3/1/1/1
GRIPPER_FORCE = 40.0      # N per finger
CUBE_SIZE = 0.04
CUBE_MASS = 0.1
TABLE_SIZE = (1.4, 1.2, 0.04)
FIXTURE_POS = (-0.35, 0.35)
TACTILE_TAXELS = 8


@dataclass
class ArmState:
    q: np.ndarray
    qd: np.ndarray
    torque: np.ndarray


class World:
    """Builds and steps the cell. Not thread-safe: the controller loop is its only user."""

    def __init__(self, seed: int = 0, render_only: bool = False, urdf_path: Optional[str] = None) -> None:
        self.seed = seed
        self.render_only = render_only
        self.p = bullet_client.BulletClient(connection_mode=pybullet.DIRECT)
        self.urdf_path = urdf_path or urdf.write_urdf()
        self.egl = render_only and self._load_egl()  # before building: EGL only sees shapes created after it
        self._build()

    def _load_egl(self) -> bool:
        import pkgutil
        try:
            egl = pkgutil.get_loader("eglRenderer")
            return egl is not None and self.p.loadPlugin(egl.get_filename(), "_eglRendererPlugin") >= 0
        except Exception:
            return False

    # ---- construction -------------------------------------------------------------------------
    def _build(self) -> None:
        p = self.p
        p.resetSimulation()
        p.setTimeStep(DT)
        p.setGravity(0, 0, -9.81)
        # Deterministic solver settings: same seed + same commands -> same trajectory.
        p.setPhysicsEngineParameter(numSolverIterations=60, deterministicOverlappingPairs=1)
        self.table = self._box((0, 0, -TABLE_SIZE[2] / 2), [s / 2 for s in TABLE_SIZE], (0.55, 0.42, 0.3, 1), mass=0)
        self._box((0, 0, -0.76), (2.5, 2.5, 0.01), (0.3, 0.3, 0.32, 1), mass=0)  # floor (camera backdrop)
        for sx in (-1, 1):  # table legs, visual context for the global camera
            for sy in (-1, 1):
                self._box((sx * 0.62, sy * 0.52, -0.4), (0.03, 0.03, 0.36), (0.25, 0.25, 0.25, 1), mass=0)
        flags = pybullet.URDF_USE_INERTIA_FROM_FILE
        self.robot = p.loadURDF(self.urdf_path, basePosition=(0, 0, 0), useFixedBase=True, flags=flags)
        names = {p.getJointInfo(self.robot, j)[1].decode(): j for j in range(p.getNumJoints(self.robot))}
        self.arm_joints = [names[n] for n in urdf.ARM_JOINTS]
        self.finger_joints = [names[n] for n in urdf.FINGER_JOINTS]
        self.ft_joint = names[urdf.FT_JOINT]
        self.all_joints = self.arm_joints + self.finger_joints
        link_names = {p.getJointInfo(self.robot, j)[12].decode(): j for j in range(p.getNumJoints(self.robot))}
        self.tactile_link = link_names[urdf.TACTILE_LINK]
        self.flange_link = link_names["flange"]
        self.elbow_link = link_names["link_3"]
        self.finger_links = [link_names["finger_left"], link_names["finger_right"]]
        for j in self.all_joints:  # disable the default velocity motors; we command every joint
            p.setJointMotorControl2(self.robot, j, pybullet.VELOCITY_CONTROL, force=0)
        for j, q in zip(self.arm_joints, HOME_Q):
            p.resetJointState(self.robot, j, q)
        for link in self.finger_links:
            p.changeDynamics(self.robot, link, lateralFriction=1.2, spinningFriction=0.01)
        # The fingers are coupled, as on a real parallel gripper (one drive through a rack or linkage): they move
        # together, so a gripped part stays centred. Two independent position-controlled fingers clamping a part
        # both push with their full force wherever it is, and the part slid from finger to finger when lifted.
        gear = p.createConstraint(self.robot, self.finger_joints[0], self.robot, self.finger_joints[1],
                                  pybullet.JOINT_GEAR, (0, 1, 0), (0, 0, 0), (0, 0, 0))
        p.changeConstraint(gear, gearRatio=-1, erp=0.2, maxForce=10 * GRIPPER_FORCE)
        p.enableJointForceTorqueSensor(self.robot, self.ft_joint, True)
        self._build_fixture()
        rng = np.random.default_rng(self.seed)
        self.cubes = []
        colors = [(0.85, 0.15, 0.15, 1), (0.15, 0.7, 0.2, 1), (0.2, 0.3, 0.9, 1)]
        for i in range(3):
            x = -0.45 + rng.uniform(-0.03, 0.03)
            y = -0.25 + 0.12 * i + rng.uniform(-0.02, 0.02)
            yaw = rng.uniform(-0.3, 0.3)
            cube = self._box((x, y, CUBE_SIZE / 2), (CUBE_SIZE / 2,) * 3, colors[i], mass=CUBE_MASS,
                             orn=p.getQuaternionFromEuler((0, 0, yaw)))
            p.changeDynamics(cube, -1, lateralFriction=1.0, spinningFriction=0.005)
            self.cubes.append(cube)
        self.arm_targets = np.array(HOME_Q)
        self.arm_target_vel = np.zeros(6)
        self.gripper_closed = False
        self.gripper_frozen = False
        self._command_fingers()
        self.hold(np.array(HOME_Q))

    def _box(self, pos: Sequence[float], half: Sequence[float], rgba: Sequence[float], mass: float,
             orn: Sequence[float] = (0, 0, 0, 1)) -> int:
        p = self.p
        col = p.createCollisionShape(pybullet.GEOM_BOX, halfExtents=half)
        vis = p.createVisualShape(pybullet.GEOM_BOX, halfExtents=half, rgbaColor=rgba)
        return p.createMultiBody(baseMass=mass, baseCollisionShapeIndex=col, baseVisualShapeIndex=vis,
                                 basePosition=pos, baseOrientation=orn)

    def _build_fixture(self) -> None:
        """A plate with three square pockets (walls 1.5 cm high) that take one cube each."""
        p = self.p
        pocket = CUBE_SIZE + 0.008
        wall = 0.01
        h = 0.015
        halves, positions = [], []
        halves.append((0.1, (3 * pocket + 4 * wall) / 2, 0.003))
        positions.append((0, 0, 0.003))
        span = 3 * pocket + 4 * wall
        for sx in (-1, 1):  # long walls
            halves.append((wall / 2, span / 2, h / 2))
            positions.append((sx * (pocket / 2 + wall / 2), 0, 0.006 + h / 2))
        for k in range(4):  # cross walls between pockets
            y = -span / 2 + wall / 2 + k * (pocket + wall)
            halves.append((pocket / 2 + wall, wall / 2, h / 2))
            positions.append((0, y, 0.006 + h / 2))
        col = p.createCollisionShapeArray([pybullet.GEOM_BOX] * len(halves), halfExtents=halves,
                                          collisionFramePositions=positions)
        vis = p.createVisualShapeArray([pybullet.GEOM_BOX] * len(halves), halfExtents=halves,
                                       visualFramePositions=positions, rgbaColors=[(0.6, 0.6, 0.65, 1)] * len(halves))
        self.fixture = p.createMultiBody(baseMass=0, baseCollisionShapeIndex=col, baseVisualShapeIndex=vis,
                                         basePosition=(FIXTURE_POS[0], FIXTURE_POS[1], 0))
        self.fixture_slots = [(FIXTURE_POS[0], FIXTURE_POS[1] - span / 2 + wall + pocket / 2 + k * (pocket + wall))
                              for k in range(3)]

    # ---- commands -----------------------------------------------------------------------------
    def command_arm(self, q: np.ndarray, qd: np.ndarray) -> None:
        """Joint position control toward q with feed-forward velocity qd (the motion planner's setpoint)."""
        self.arm_targets = np.asarray(q, dtype=float)
        self.arm_target_vel = np.asarray(qd, dtype=float)
        self.p.setJointMotorControlArray(self.robot, self.arm_joints, pybullet.POSITION_CONTROL,
                                         targetPositions=list(self.arm_targets),
                                         targetVelocities=list(self.arm_target_vel),
                                         forces=list(ARM_FORCES), positionGains=[0.6] * 6, velocityGains=[1.0] * 6)

    def hold(self, q: np.ndarray) -> None:
        self.command_arm(q, np.zeros(6))

    def set_gripper(self, closed: bool) -> None:
        if self.gripper_frozen or closed == self.gripper_closed:
            return
        self.gripper_closed = closed
        self._command_fingers()

    def freeze_gripper(self, frozen: bool) -> None:
        """A gripper fault: the fingers stop where they are and ignore commands until reset."""
        self.gripper_frozen = frozen
        if frozen:
            for j in self.finger_joints:
                q = self.p.getJointState(self.robot, j)[0]
                self.p.setJointMotorControl2(self.robot, j, pybullet.POSITION_CONTROL, targetPosition=q,
                                             force=GRIPPER_FORCE, maxVelocity=0.1)
        else:
            self._command_fingers()

    def _command_fingers(self) -> None:
        target = 0.0 if self.gripper_closed else urdf.FINGER_TRAVEL
        for j in self.finger_joints:
            self.p.setJointMotorControl2(self.robot, j, pybullet.POSITION_CONTROL, targetPosition=target,
                                         force=GRIPPER_FORCE, maxVelocity=0.12, positionGain=0.3)

    def step(self) -> None:
        self.p.stepSimulation()

    # ---- readings -----------------------------------------------------------------------------
    def arm_state(self) -> ArmState:
        states = self.p.getJointStates(self.robot, self.arm_joints)
        return ArmState(q=np.array([s[0] for s in states]), qd=np.array([s[1] for s in states]),
                        torque=np.array([s[3] for s in states]))

    def tcp_state(self, tcp_pos: Sequence[float], tcp_orn: Sequence[float]):
        """TCP pose and twist from the physics' own forward kinematics (C++; the base frame is the world frame).

        Returns (flange position, flange quaternion, TCP position, TCP quaternion, linear velocity, angular velocity).
        """
        p = self.p
        ls = p.getLinkState(self.robot, self.flange_link, computeLinkVelocity=1, computeForwardKinematics=1)
        pos, orn, v, w = ls[4], ls[5], ls[6], ls[7]
        tpos, torn = p.multiplyTransforms(pos, orn, tcp_pos, tcp_orn)
        r = (tpos[0] - pos[0], tpos[1] - pos[1], tpos[2] - pos[2])
        v_tcp = (v[0] + w[1] * r[2] - w[2] * r[1], v[1] + w[2] * r[0] - w[0] * r[2], v[2] + w[0] * r[1] - w[1] * r[0])
        return pos, orn, tpos, torn, v_tcp, w

    def elbow_position(self) -> tuple:
        return self.p.getLinkState(self.robot, self.elbow_link, computeForwardKinematics=1)[4]

    def finger_positions(self) -> list[float]:
        return [s[0] for s in self.p.getJointStates(self.robot, self.finger_joints)]

    def ft_wrench(self) -> np.ndarray:
        """Reaction wrench at the F/T joint, sensor frame (Fx Fy Fz Tx Ty Tz): what the gripper pulls on the wrist."""
        return np.array(self.p.getJointState(self.robot, self.ft_joint)[2])

    def tactile(self) -> tuple[list[float], list[float]]:
        """Pressure profile along the left finger pad: x = taxel centre (mm from finger root), y = force (N)."""
        p = self.p
        pos, orn = p.getLinkState(self.robot, self.tactile_link)[4:6]
        inv_pos, inv_orn = p.invertTransform(pos, orn)
        forces = [0.0] * TACTILE_TAXELS
        for c in p.getContactPoints(bodyA=self.robot, linkIndexA=self.tactile_link):
            if c[2] == self.robot:
                continue
            local, _ = p.multiplyTransforms(inv_pos, inv_orn, c[5], (0, 0, 0, 1))
            k = int(local[2] / urdf.FINGER_LENGTH * TACTILE_TAXELS)
            if 0 <= k < TACTILE_TAXELS:
                forces[k] += c[9]
        xs = [(k + 0.5) * urdf.FINGER_LENGTH / TACTILE_TAXELS * 1000 for k in range(TACTILE_TAXELS)]
        return xs, forces

    def body_poses(self) -> list[tuple[tuple, tuple]]:
        return [self.p.getBasePositionAndOrientation(c) for c in self.cubes]

    def snapshot(self) -> tuple[list[float], list[tuple[tuple, tuple]]]:
        """What a render replica needs: every robot joint position and every free body's pose."""
        joints = [s[0] for s in self.p.getJointStates(self.robot, self.all_joints)]
        return joints, self.body_poses()

    def apply_snapshot(self, snap: tuple[list[float], list[tuple[tuple, tuple]]]) -> None:
        joints, bodies = snap
        for j, q in zip(self.all_joints, joints):
            self.p.resetJointState(self.robot, j, q)
        for body, (pos, orn) in zip(self.cubes, bodies):
            self.p.resetBasePositionAndOrientation(body, pos, orn)

    def close(self) -> None:
        try:
            self.p.disconnect()
        except Exception:  # already gone
            pass
