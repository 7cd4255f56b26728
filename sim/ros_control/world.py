"""The ros_control cell's physics: sim/world.py's table, parts and fixtures with the pybullet_data arm instead of the
UR5, its vacuum cup working like the UR vacuum tool (a fixed constraint while the cup face touches a part and the
suction is on: RobotArm's vacuum code, reused).
"""
from __future__ import annotations

from typing import Optional, Sequence

import numpy as np
import pybullet

from ..scene import ArmSpec, yaw_quaternion
from ..world import RobotArm, World
from . import model as mdl
from .spec import RosControlArm, RosControlWorld

POSITION_GAIN = 0.6   # PyBullet's position motor (as the UR sim): stiff enough to track within a milliradian
VELOCITY_GAIN = 1.0


class IiwaArm(RobotArm):
    """One ros_control arm: position-controlled joints (the desired position and velocity each step), the wrist F/T
    reading at the flange, the suction cup. A collision fault blocks it where it stands."""

    def __init__(self, world: World, spec: ArmSpec, robot: RosControlArm) -> None:
        p = world.p
        self.world, self.p, self.spec, self.ros_arm = world, p, spec, robot
        self.group = spec.group
        self.tool = "vacuum"
        self.at_origin = spec.at_origin
        self.base_pos, self.base_orn = tuple(spec.base), yaw_quaternion(spec.yaw)
        self._inv_base = p.invertTransform(self.base_pos, self.base_orn)
        self._base_rot = np.array(p.getMatrixFromQuaternion(self.base_orn)).reshape(3, 3)
        path = mdl.write_urdf(world.urdf_dir, robot.model, robot.rename_map, robot.ros.tip_link, robot.tool_length,
                              tag=robot.group)
        self.robot = p.loadURDF(path, basePosition=self.base_pos, baseOrientation=self.base_orn, useFixedBase=True,
                                flags=pybullet.URDF_USE_INERTIA_FROM_FILE)
        infos = [p.getJointInfo(self.robot, j) for j in range(p.getNumJoints(self.robot))]
        joints = {i[1].decode(): i[0] for i in infos}
        links = {i[12].decode(): i[0] for i in infos}
        self.arm_joints = [joints[n] for n in robot.model.joint_names]
        self.finger_joints: list[int] = []
        self.all_joints = list(self.arm_joints)
        self.ft_joint = joints[mdl.ft_joint(robot.model)]
        self.flange_link = links[mdl.ft_link(robot.model)]
        self.cup_link = links[robot.ros.tip_link]
        self.tactile_link = None
        self.finger_links: list[int] = []
        self.forces = [j.effort for j in robot.model.joints]
        self.max_velocities = [j.velocity for j in robot.model.joints]
        for j in self.arm_joints:  # disable the default velocity motors; we command every joint
            p.setJointMotorControl2(self.robot, j, pybullet.VELOCITY_CONTROL, force=0)
        self.start_q = tuple(robot.start_joints)
        for j, q in zip(self.arm_joints, self.start_q):
            p.resetJointState(self.robot, j, q)
        p.enableJointForceTorqueSensor(self.robot, self.ft_joint, True)
        n = len(self.arm_joints)
        self.arm_targets = np.array(self.start_q)
        self.arm_target_vel = np.zeros(n)
        self.gripper_closed = False   # suction on
        self.gripper_frozen = False   # vacuum fault: the suction ignores its output
        self.held: Optional[int] = None
        self._held_constraint: Optional[int] = None
        self.blocked: Optional[np.ndarray] = None  # collision fault: the pose the arm is stuck in

    def start(self) -> None:
        self.hold(np.array(self.start_q))

    def command_arm(self, q: np.ndarray, qd: np.ndarray) -> None:
        """Position control toward q with feed-forward qd (the controller's desired state); the model's effort and
        velocity limits apply. A blocked arm (collision) stays where it is, whatever is commanded."""
        if self.blocked is not None:
            q, qd = self.blocked, np.zeros(len(self.arm_joints))
        self.arm_targets = np.asarray(q, dtype=float)
        self.arm_target_vel = np.clip(np.asarray(qd, dtype=float), -np.array(self.max_velocities),
                                      self.max_velocities)
        n = len(self.arm_joints)
        self.p.setJointMotorControlArray(self.robot, self.arm_joints, pybullet.POSITION_CONTROL,
                                         targetPositions=list(self.arm_targets),
                                         targetVelocities=list(self.arm_target_vel), forces=self.forces,
                                         positionGains=[POSITION_GAIN] * n, velocityGains=[VELOCITY_GAIN] * n)

    def hold(self, q: np.ndarray) -> None:
        self.command_arm(q, np.zeros(len(self.arm_joints)))

    def read(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """q, qd, applied joint torques, and the wrist wrench (Fx Fy Fz Tx Ty Tz at the flange), in one query."""
        states = self.p.getJointStates(self.robot, self.arm_joints + [self.ft_joint])
        arm = states[:-1]
        return (np.array([s[0] for s in arm]), np.array([s[1] for s in arm]), np.array([s[3] for s in arm]),
                np.array(states[-1][2]))

    def tcp_pose(self) -> tuple[Sequence[float], Sequence[float]]:
        """The tip link (cup face) in this arm's base frame."""
        pos, orn = self.p.getLinkState(self.robot, self.cup_link, computeForwardKinematics=1)[4:6]
        return self.p.multiplyTransforms(self._inv_base[0], self._inv_base[1], pos, orn)


class IiwaWorld(World):
    """sim/world.py's cell with the ros_control arms (also the camera process's render replica)."""

    spec: RosControlWorld

    def _make_arm(self, spec: ArmSpec) -> RobotArm:
        return IiwaArm(self, spec, self.spec.robot(spec.group))
