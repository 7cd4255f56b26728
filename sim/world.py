"""The physical cell in PyBullet: UR5 arms (each with an F/T sensor and a gripper or a vacuum tool), a table,
graspable cubes, stations (fixtures with pockets, flat stands).

What is built comes from a WorldSpec (sim/scene.py; the cell file's `simulation:` section; the stations' geometry:
sim/stations.py, shared with the scene markers). The default is the demo world: one arm at the origin with the
two-finger gripper, three cubes from the seed, a three-pocket fixture.
One World owns one PyBullet client (DIRECT, headless): every arm of the cell lives in this one physics world (a part
handed over from one arm to the other is in both their reach), stepped once per controller tick.
The same construction code builds the render-only replica used by the camera process.
"""
from __future__ import annotations

import math
import tempfile
from dataclasses import dataclass
from typing import Optional, Sequence

import numpy as np
import pybullet
from pybullet_utils import bullet_client

from . import urdf
from .scene import DEFAULT_WORLD, PART_COLORS, ArmSpec, PartsSpec, StationSpec, WorldSpec, yaw_quaternion
from .stations import station_shape

PHYSICS_HZ = 500          # fixed physics step; also the controller tick (UR e-Series runs at 500 Hz)
DT = 1.0 / PHYSICS_HZ
HOME_Q = (0.0, -1.5708, 1.5708, -1.5708, -1.5708, 0.0)
ARM_FORCES = (330.0, 330.0, 150.0, 56.0, 56.0, 56.0)   # max joint torques (N m), UR5 sizes 3/3/3/1/1/1
GRIPPER_FORCE = 40.0      # N per finger
CUBE_SIZE = 0.04          # the demo's parts (PartsSpec.size)
CUBE_MASS = 0.1
TABLE_SIZE = (1.4, 1.2, 0.04)
FIXTURE_POS = (-0.35, 0.35)
TACTILE_TAXELS = 8
# Vacuum: a part is sucked on when its face is within VACUUM_REACH of the cup face (or up to VACUUM_PRESS into it,
# pressed), its centre within VACUUM_CENTRE of the cup axis and that face square to the cup within VACUUM_TILT.
VACUUM_REACH = 0.005
VACUUM_PRESS = 0.003
VACUUM_CENTRE = 0.012
VACUUM_TILT = math.radians(15)
VACUUM_FORCE = 40.0       # N the suction holds with (a held 0.1 kg cube needs 1 N; a collision tears it off less)


def restock_text(moved: int, kept: int) -> str:
    """What /sim/restock answers."""
    one = kept == 1
    held = f"; {kept} left where {'it is' if one else 'they are'}: a robot holds or touches {'it' if one else 'them'}"
    return f"{moved} part{'' if moved == 1 else 's'} put back" + (held if kept else "")


@dataclass
class ArmState:
    q: np.ndarray
    qd: np.ndarray
    torque: np.ndarray


class RobotArm:
    """One UR5 in the world, with its tool. Its readings are in its own base frame, like a UR controller's."""

    def __init__(self, world: "World", spec: ArmSpec) -> None:
        p = world.p
        self.world, self.p, self.spec = world, p, spec
        self.group = spec.group
        self.tool = spec.tool.kind
        self.at_origin = spec.at_origin
        self.base_pos, self.base_orn = tuple(spec.base), yaw_quaternion(spec.yaw)
        self._inv_base = p.invertTransform(self.base_pos, self.base_orn)
        self._base_rot = np.array(p.getMatrixFromQuaternion(self.base_orn)).reshape(3, 3)
        flags = pybullet.URDF_USE_INERTIA_FROM_FILE
        self.robot = p.loadURDF(urdf.write_urdf(world.urdf_dir, self.tool), basePosition=self.base_pos,
                                baseOrientation=self.base_orn, useFixedBase=True, flags=flags)
        names = {p.getJointInfo(self.robot, j)[1].decode(): j for j in range(p.getNumJoints(self.robot))}
        link_names = {p.getJointInfo(self.robot, j)[12].decode(): j for j in range(p.getNumJoints(self.robot))}
        self.arm_joints = [names[n] for n in urdf.ARM_JOINTS]
        self.finger_joints = [names[n] for n in urdf.FINGER_JOINTS] if self.tool == "gripper" else []
        self.ft_joint = names[urdf.FT_JOINT]
        self.all_joints = self.arm_joints + self.finger_joints
        self.flange_link = link_names["flange"]
        self.elbow_link = link_names["link_3"]
        self.tactile_link = link_names[urdf.TACTILE_LINK] if self.tool == "gripper" else None
        self.finger_links = [link_names["finger_left"], link_names["finger_right"]] if self.tool == "gripper" else []
        self.cup_link = link_names[urdf.CUP_LINK] if self.tool == "vacuum" else None
        for j in self.all_joints:  # disable the default velocity motors; we command every joint
            p.setJointMotorControl2(self.robot, j, pybullet.VELOCITY_CONTROL, force=0)
        self.start_q = HOME_Q if spec.start_joints is None else tuple(spec.start_joints)
        for j, q in zip(self.arm_joints, self.start_q):
            p.resetJointState(self.robot, j, q)
        for link in self.finger_links:
            p.changeDynamics(self.robot, link, lateralFriction=1.2, spinningFriction=0.01)
        if self.tool == "gripper":
            # The fingers are coupled, as on a real parallel gripper (one drive through a rack or linkage): they move
            # together, so a gripped part stays centred. Two independent position-controlled fingers clamping a part
            # both push with their full force wherever it is, and the part slid from finger to finger when lifted.
            gear = p.createConstraint(self.robot, self.finger_joints[0], self.robot, self.finger_joints[1],
                                      pybullet.JOINT_GEAR, (0, 1, 0), (0, 0, 0), (0, 0, 0))
            p.changeConstraint(gear, gearRatio=-1, erp=0.2, maxForce=10 * GRIPPER_FORCE)
        p.enableJointForceTorqueSensor(self.robot, self.ft_joint, True)
        self.arm_targets = np.array(self.start_q)
        self.arm_target_vel = np.zeros(6)
        self.gripper_closed = False   # gripper: closed commanded; vacuum: suction on
        self.gripper_frozen = False   # a tool fault: the tool ignores its output
        self.held: Optional[int] = None        # vacuum: the part on the cup
        self._held_constraint: Optional[int] = None

    def start(self) -> None:
        """Command the tool and hold the home configuration (after the whole world is built)."""
        if self.tool == "gripper":
            self._command_fingers()
        self.hold(np.array(self.start_q))

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

    def set_tool(self, on: bool) -> None:
        """The tool's digital output: closes the gripper, or switches the suction on."""
        if self.tool == "vacuum":
            self.set_suction(on)
        else:
            self.set_gripper(on)

    def set_gripper(self, closed: bool) -> None:
        if self.gripper_frozen or closed == self.gripper_closed:
            return
        self.gripper_closed = closed
        self._command_fingers()

    def freeze_gripper(self, frozen: bool) -> None:
        """A tool fault: the fingers stop where they are (the suction stays as it is) and ignore commands until reset."""
        self.gripper_frozen = frozen
        if self.tool != "gripper":
            return
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

    # ---- vacuum -------------------------------------------------------------------------------
    def set_suction(self, on: bool) -> None:
        """Suction on: pick up a part lying square under the cup (checked every tick while on); off: let go."""
        if self.gripper_frozen:
            return
        self.gripper_closed = on
        if not on:
            self._release()
        elif self.held is None:
            self._try_attach()

    def _try_attach(self) -> None:
        p = self.p
        face_pos, face_orn = p.getLinkState(self.robot, self.cup_link, computeForwardKinematics=1)[4:6]
        rot = np.array(p.getMatrixFromQuaternion(face_orn)).reshape(3, 3)
        axis = rot[:, 2]  # out of the cup, toward the part
        half = self.world.parts_spec.size / 2
        for part in self.world.cubes:
            if self.world.holder_of(part) is not None:
                continue
            pos, orn = p.getBasePositionAndOrientation(part)
            rel = np.asarray(pos) - np.asarray(face_pos)
            depth = float(rel @ axis)  # cup face to the part's centre, along the cup axis
            gap = depth - half
            if not -VACUUM_PRESS <= gap <= VACUUM_REACH:
                continue
            if float(np.linalg.norm(rel - depth * axis)) > VACUUM_CENTRE:
                continue
            part_rot = np.array(p.getMatrixFromQuaternion(orn)).reshape(3, 3)
            if float(np.max(np.abs(part_rot.T @ axis))) < math.cos(VACUUM_TILT):
                continue  # no face of the cube lies flat against the cup
            self._attach(part, face_pos, face_orn, rel, axis, half, rot)
            return

    def _attach(self, part: int, face_pos, face_orn, rel: np.ndarray, axis: np.ndarray, half: float,
                rot: np.ndarray) -> None:
        """A fixed constraint pulls the part's face against the cup (centred where it was, turned as it was)."""
        p = self.p
        lateral = rel - float(rel @ axis) * axis
        in_cup = rot.T @ (lateral + half * axis)  # where the part's centre will be, in the cup frame
        inv_pos, inv_orn = p.invertTransform(face_pos, face_orn)
        _, rel_orn = p.multiplyTransforms(inv_pos, inv_orn, (0, 0, 0), p.getBasePositionAndOrientation(part)[1])
        p.setCollisionFilterPair(self.robot, part, self.cup_link, -1, 0)
        cid = p.createConstraint(self.robot, self.cup_link, part, -1, pybullet.JOINT_FIXED, (0, 0, 0),
                                 tuple(float(v) for v in in_cup), (0, 0, 0), rel_orn, (0, 0, 0, 1))
        p.changeConstraint(cid, maxForce=VACUUM_FORCE)
        self.held, self._held_constraint = part, cid

    def _release(self) -> None:
        if self.held is None:
            return
        self.p.removeConstraint(self._held_constraint)
        self.p.setCollisionFilterPair(self.robot, self.held, self.cup_link, -1, 1)
        self.held, self._held_constraint = None, None

    def tick_tool(self) -> None:
        """Per tick: the switched-on suction takes a part that has come under the cup."""
        if self.tool == "vacuum" and self.gripper_closed and self.held is None and not self.gripper_frozen:
            self._try_attach()

    # ---- readings -----------------------------------------------------------------------------
    def arm_state(self) -> ArmState:
        states = self.p.getJointStates(self.robot, self.arm_joints)
        return ArmState(q=np.array([s[0] for s in states]), qd=np.array([s[1] for s in states]),
                        torque=np.array([s[3] for s in states]))

    def tcp_state(self, tcp_pos: Sequence[float], tcp_orn: Sequence[float]):
        """TCP pose and twist from the physics' own forward kinematics (C++), in this arm's base frame.

        Returns (flange position, flange quaternion, TCP position, TCP quaternion, linear velocity, angular velocity).
        """
        p = self.p
        ls = p.getLinkState(self.robot, self.flange_link, computeLinkVelocity=1, computeForwardKinematics=1)
        pos, orn, v, w = ls[4], ls[5], ls[6], ls[7]
        if not self.at_origin:  # world -> base frame
            pos, orn = p.multiplyTransforms(self._inv_base[0], self._inv_base[1], pos, orn)
            v, w = tuple(self._base_rot.T @ np.asarray(v)), tuple(self._base_rot.T @ np.asarray(w))
        tpos, torn = p.multiplyTransforms(pos, orn, tcp_pos, tcp_orn)
        r = (tpos[0] - pos[0], tpos[1] - pos[1], tpos[2] - pos[2])
        v_tcp = (v[0] + w[1] * r[2] - w[2] * r[1], v[1] + w[2] * r[0] - w[0] * r[2], v[2] + w[0] * r[1] - w[1] * r[0])
        return pos, orn, tpos, torn, v_tcp, w

    def elbow_position(self) -> tuple:
        pos = self.p.getLinkState(self.robot, self.elbow_link, computeForwardKinematics=1)[4]
        if not self.at_origin:
            pos = self.p.multiplyTransforms(self._inv_base[0], self._inv_base[1], pos, (0, 0, 0, 1))[0]
        return pos

    def finger_positions(self) -> list[float]:
        if not self.finger_joints:
            return []
        return [s[0] for s in self.p.getJointStates(self.robot, self.finger_joints)]

    def ft_wrench(self) -> np.ndarray:
        """Reaction wrench at the F/T joint, sensor frame (Fx Fy Fz Tx Ty Tz): what the tool pulls on the wrist."""
        return np.array(self.p.getJointState(self.robot, self.ft_joint)[2])

    def tactile(self) -> tuple[list[float], list[float]]:
        """Pressure profile along the left finger pad: x = taxel centre (mm from finger root), y = force (N)."""
        p = self.p
        xs = [(k + 0.5) * urdf.FINGER_LENGTH / TACTILE_TAXELS * 1000 for k in range(TACTILE_TAXELS)]
        forces = [0.0] * TACTILE_TAXELS
        if self.tactile_link is None:
            return xs, forces
        pos, orn = p.getLinkState(self.robot, self.tactile_link)[4:6]
        inv_pos, inv_orn = p.invertTransform(pos, orn)
        for c in p.getContactPoints(bodyA=self.robot, linkIndexA=self.tactile_link):
            if c[2] == self.robot:
                continue
            local, _ = p.multiplyTransforms(inv_pos, inv_orn, c[5], (0, 0, 0, 1))
            k = int(local[2] / urdf.FINGER_LENGTH * TACTILE_TAXELS)
            if 0 <= k < TACTILE_TAXELS:
                forces[k] += c[9]
        return xs, forces

    def joint_positions(self) -> list[float]:
        return [s[0] for s in self.p.getJointStates(self.robot, self.all_joints)]

    def set_joint_positions(self, joints: Sequence[float]) -> None:
        for j, q in zip(self.all_joints, joints):
            self.p.resetJointState(self.robot, j, q)


class World:
    """Builds and steps the cell. Not thread-safe: the controller loop is its only user."""

    def __init__(self, seed: int = 0, render_only: bool = False, urdf_dir: Optional[str] = None,
                 spec: WorldSpec = DEFAULT_WORLD) -> None:
        self.seed = seed
        self.spec = spec
        self.parts_spec: PartsSpec = spec.parts
        self.render_only = render_only
        self.p = bullet_client.BulletClient(connection_mode=pybullet.DIRECT)
        self.urdf_dir = urdf_dir or tempfile.mkdtemp(prefix="sim-urdf-")
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
        self.arms = [self._make_arm(a) for a in self.spec.arms]
        self.stations: dict[str, int] = {}
        self.pockets: dict[str, list[tuple[float, float]]] = {}
        for st in self.spec.stations:
            if st.kind == "stand":
                self.stations[st.name] = self._build_stand(st)
            else:
                self.stations[st.name], self.pockets[st.name] = self._build_fixture(st)
        fixtures = [st.name for st in self.spec.stations if st.kind == "fixture"]
        self.fixture = self.stations[fixtures[0]] if fixtures else None
        self.fixture_slots = self.pockets[fixtures[0]] if fixtures else []
        self.cubes = self._build_parts(self.spec.parts)
        self.part_homes = [self.p.getBasePositionAndOrientation(c) for c in self.cubes]
        for arm in self.arms:
            arm.start()

    def _make_arm(self, spec: ArmSpec) -> RobotArm:
        """The arm on the table (a subclass builds another robot: sim/ros_control/world.py)."""
        return RobotArm(self, spec)

    def _box(self, pos: Sequence[float], half: Sequence[float], rgba: Sequence[float], mass: float,
             orn: Sequence[float] = (0, 0, 0, 1)) -> int:
        p = self.p
        col = p.createCollisionShape(pybullet.GEOM_BOX, halfExtents=half)
        vis = p.createVisualShape(pybullet.GEOM_BOX, halfExtents=half, rgbaColor=rgba)
        return p.createMultiBody(baseMass=mass, baseCollisionShapeIndex=col, baseVisualShapeIndex=vis,
                                 basePosition=pos, baseOrientation=orn)

    def _build_parts(self, spec: PartsSpec) -> list[int]:
        p = self.p
        rng = np.random.default_rng(self.seed)
        cubes = []
        jx, jy, jyaw = spec.jitter
        for i in range(spec.number):
            if spec.positions is not None:
                x0, y0, yaw0 = spec.positions[i]
            else:
                x0 = spec.start[0] + spec.step[0] * i
                y0 = spec.start[1] + spec.step[1] * i
                yaw0 = 0.0
            # Drawn in this order (x, y, yaw) per part: the demo's placement for a seed depends on it.
            x = x0 + rng.uniform(-jx, jx)
            y = y0 + rng.uniform(-jy, jy)
            yaw = yaw0 + rng.uniform(-jyaw, jyaw)
            cube = self._box((x, y, spec.size / 2), (spec.size / 2,) * 3, PART_COLORS[i % len(PART_COLORS)],
                             mass=spec.mass, orn=p.getQuaternionFromEuler((0, 0, yaw)))
            p.changeDynamics(cube, -1, lateralFriction=1.0, spinningFriction=0.005)
            cubes.append(cube)
        return cubes

    def _build_stand(self, st: StationSpec) -> int:
        shape = station_shape(st, self.spec.parts.size)
        return self._box(shape.base_pos, shape.halves[0], shape.rgba, mass=0, orn=shape.base_orn)

    def _build_fixture(self, st: StationSpec) -> tuple[int, list[tuple[float, float]]]:
        """A plate with square pockets (walls 1.5 cm high) that take one part each (sim/stations.py: a row of N
        pockets along the station's y axis, or one walled pocket at each given world position on a common plate)."""
        p = self.p
        shape = station_shape(st, self.spec.parts.size)
        n = len(shape.halves)
        frames = {} if shape.orns is None else {"collisionFrameOrientations": list(shape.orns)}
        col = p.createCollisionShapeArray([pybullet.GEOM_BOX] * n, halfExtents=list(shape.halves),
                                          collisionFramePositions=list(shape.positions), **frames)
        vis_frames = {} if shape.orns is None else {"visualFrameOrientations": list(shape.orns)}
        vis = p.createVisualShapeArray([pybullet.GEOM_BOX] * n, halfExtents=list(shape.halves),
                                       visualFramePositions=list(shape.positions), rgbaColors=[shape.rgba] * n,
                                       **vis_frames)
        body = p.createMultiBody(baseMass=0, baseCollisionShapeIndex=col, baseVisualShapeIndex=vis,
                                 basePosition=shape.base_pos, baseOrientation=shape.base_orn)
        return body, list(shape.slots)

    # ---- the demo's single arm (and tests written for it) ------------------------------------
    @property
    def arm(self) -> RobotArm:
        return self.arms[0]

    @property
    def robot(self) -> int:
        return self.arms[0].robot

    @property
    def arm_joints(self) -> list[int]:
        return self.arms[0].arm_joints

    @property
    def ft_joint(self) -> int:
        return self.arms[0].ft_joint

    def arm_state(self) -> ArmState:
        return self.arms[0].arm_state()

    def arm_for(self, group: str) -> RobotArm:
        for a in self.arms:
            if a.group == group:
                return a
        raise KeyError(group)

    # ---- stepping and readings ----------------------------------------------------------------
    def step(self) -> None:
        self.p.stepSimulation()

    def holder_of(self, part: int) -> Optional[RobotArm]:
        """The arm whose suction cup holds this part (None: none)."""
        for a in self.arms:
            if a.held == part:
                return a
        return None

    def restock(self) -> tuple[int, int]:
        """What a feeder (or an operator refilling the cell) does: every part no robot touches goes back where it lay
        at the start. Returns (parts put back, parts left where they are because a robot holds or touches them)."""
        moved = kept = 0
        for cube, (pos, orn) in zip(self.cubes, self.part_homes):
            if self.holder_of(cube) is not None or any(self.p.getContactPoints(bodyA=cube, bodyB=a.robot)
                                                       for a in self.arms):
                kept += 1
                continue
            self.p.resetBasePositionAndOrientation(cube, pos, orn)
            self.p.resetBaseVelocity(cube, (0, 0, 0), (0, 0, 0))
            moved += 1
        return moved, kept

    def body_poses(self) -> list[tuple[tuple, tuple]]:
        """The parts' poses in the world frame, in creation order."""
        return [self.p.getBasePositionAndOrientation(c) for c in self.cubes]

    def snapshot(self) -> tuple[list[float], list[tuple[tuple, tuple]]]:
        """What a render replica needs: every robot joint position (arm by arm) and every free body's pose."""
        joints = [q for a in self.arms for q in a.joint_positions()]
        return joints, self.body_poses()

    def apply_snapshot(self, snap: tuple[list[float], list[tuple[tuple, tuple]]]) -> None:
        joints, bodies = snap
        k = 0
        for a in self.arms:
            n = len(a.all_joints)
            a.set_joint_positions(joints[k:k + n])
            k += n
        for body, (pos, orn) in zip(self.cubes, bodies):
            self.p.resetBasePositionAndOrientation(body, pos, orn)

    def close(self) -> None:
        try:
            self.p.disconnect()
        except Exception:  # already gone
            pass
