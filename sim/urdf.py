"""Generate the UR5 + F/T sensor + tool URDF from the DH parameters (primitive shapes).

Each revolute joint i sits at DH frame i-1 and turns about its z axis; the fixed offset to the next joint is
Tz(d_i) Tx(a_i) Rx(alpha_i), so the URDF reproduces the DH forward kinematics exactly.
Tools: the two-finger gripper (the demo's) or a vacuum tool (a body and a short suction cup; TCP at the cup face).
"""
from __future__ import annotations

import math
import os
import tempfile
from typing import Optional, Sequence
from xml.sax.saxutils import quoteattr

from . import kinematics as kin

# Gripper geometry (metres), all along the flange z axis.
FT_LENGTH = 0.02          # force/torque sensor disk between flange and gripper
GRIPPER_BASE = 0.04       # gripper body height
FINGER_LENGTH = 0.08
FINGER_THICK = 0.012
FINGER_WIDTH = 0.022
FINGER_TRAVEL = 0.045     # each finger's inner face: 0 (closed) .. 0.045 m from the centre
TCP_Z = FT_LENGTH + GRIPPER_BASE + FINGER_LENGTH - 0.015  # between the fingertips
DEFAULT_TCP = (0.0, 0.0, TCP_Z, 0.0, 0.0, 0.0)
# Vacuum tool: a body, then a short suction cup whose link frame is at its face.
VACUUM_BODY_LENGTH = 0.05
VACUUM_BODY_RADIUS = 0.03
CUP_LENGTH = 0.02
CUP_RADIUS = 0.016
CUP_LINK = "suction_cup"
VACUUM_TCP_Z = FT_LENGTH + VACUUM_BODY_LENGTH + CUP_LENGTH  # at the cup face
VACUUM_TCP = (0.0, 0.0, VACUUM_TCP_Z, 0.0, 0.0, 0.0)
TOOLS = ("gripper", "vacuum")

ARM_JOINTS = ["shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint",
              "wrist_1_joint", "wrist_2_joint", "wrist_3_joint"]
FINGER_JOINTS = ["finger_left_joint", "finger_right_joint"]
FT_JOINT = "ft_sensor_joint"
TACTILE_LINK = "finger_left"

_MASSES = (3.7, 8.393, 2.275, 1.219, 1.219, 0.1879)
_RADII = (0.06, 0.055, 0.045, 0.04, 0.04, 0.035)


def _inertial(mass: float, size: float = 0.05) -> str:
    i = mass * size * size / 6
    return (f'<inertial><mass value="{mass}"/><origin xyz="0 0 0"/>'
            f'<inertia ixx="{i:.6g}" iyy="{i:.6g}" izz="{i:.6g}" ixy="0" ixz="0" iyz="0"/></inertial>')


def _segment(x: float, z: float, radius: float, color: str) -> str:
    """A cylinder from the link origin to (x, 0, z) in the link frame."""
    length = math.hypot(x, z)
    if length < 1e-6:
        return ""
    pitch = math.atan2(x, z)  # rotate the cylinder's z axis onto the segment
    geo = f'<geometry><cylinder radius="{radius}" length="{length:.6f}"/></geometry>'
    org = f'<origin xyz="{x / 2:.6f} 0 {z / 2:.6f}" rpy="0 {pitch:.6f} 0"/>'
    return (f'<visual>{org}{geo}<material name="{color}"/></visual>'
            f'<collision>{org}{geo}</collision>')


def default_tcp(tool: str = "gripper") -> tuple[float, ...]:
    return VACUUM_TCP if tool == "vacuum" else DEFAULT_TCP


def _joint_disk(radius: float) -> str:
    geo = f'<geometry><cylinder radius="{radius}" length="{radius * 2.2:.4f}"/></geometry>'
    return f'<visual><origin xyz="0 0 0"/>{geo}<material name="ur_blue"/></visual>'


def ur_joint_names(group_joints: Sequence[str]) -> list[str]:
    """The names a UR arm's six joints have on /joint_states, from its motion group's `joints` (cell file
    manual.groups[].joints), as our robot driver names them (cell_nodes manual config.plan_arms): a group joint is the
    robot joint its name ends with (`left_elbow_joint` -> elbow_joint), in any order; a robot joint the group does not
    name gets the prefix of the group's first joint + its UR name. No joints: the UR names (ARM_JOINTS).
    ValueError when a name ends with no UR joint name or two names are the same robot joint."""
    named: dict[int, str] = {}
    for name in group_joints:
        index = next((i for i, j in enumerate(ARM_JOINTS) if isinstance(name, str) and name.endswith(j)), None)
        if index is None:
            raise ValueError(f"{name!r} is not a joint of the UR arm (a joint name ends with one of "
                             f"{', '.join(ARM_JOINTS)})")
        if index in named:
            raise ValueError(f"{name!r} is the same robot joint ({ARM_JOINTS[index]}) as {named[index]!r}")
        named[index] = name
    if not named:
        return list(ARM_JOINTS)
    first = group_joints[0]
    prefix = first[:len(first) - len(ARM_JOINTS[next(i for i, n in named.items() if n == first)])]
    return [named.get(i, prefix + j) for i, j in enumerate(ARM_JOINTS)]


def urdf_text(tool: str = "gripper", joint_names: Optional[Sequence[str]] = None) -> str:
    """The arm's URDF. `joint_names`: the six revolute arm joints' names, in ARM_JOINTS order (default ARM_JOINTS:
    what the physics loads); the robot_description parameter uses the names the robot driver publishes
    (ur_joint_names). Links and the tool's joints keep their names."""
    if tool not in TOOLS:
        raise ValueError(f"unknown tool {tool!r}")
    names = list(ARM_JOINTS) if joint_names is None else [str(n) for n in joint_names]
    if len(names) != len(ARM_JOINTS) or len(set(names)) != len(names) or not all(names):
        raise ValueError(f"expected {len(ARM_JOINTS)} different joint names, got {joint_names!r}")
    others = set(FINGER_JOINTS) | {FT_JOINT, "flange_joint", "gripper_mount", "vacuum_mount", "cup_mount"}
    if others & set(names):
        raise ValueError(f"joint names {sorted(others & set(names))} are the tool's")
    parts = ['<?xml version="1.0"?>', '<robot name="ur5_cell_arm">',
             '<material name="ur_grey"><color rgba="0.75 0.75 0.78 1"/></material>',
             '<material name="ur_blue"><color rgba="0.2 0.45 0.75 1"/></material>',
             '<material name="dark"><color rgba="0.15 0.15 0.15 1"/></material>',
             '<material name="pad"><color rgba="0.9 0.5 0.1 1"/></material>']
    base_geo = '<geometry><cylinder radius="0.075" length="0.04"/></geometry>'
    parts.append(f'<link name="base_link">{_inertial(4.0)}'
                 f'<visual><origin xyz="0 0 0.02"/>{base_geo}<material name="ur_grey"/></visual>'
                 f'<collision><origin xyz="0 0 0.02"/>{base_geo}</collision></link>')
    parent, origin = "base_link", (0.0, 0.0, 0.0, 0.0)  # (x, z, roll) of this joint in the parent link
    for i in range(6):
        link = f"link_{i + 1}"
        x_next, z_next = kin.A[i], kin.D[i]
        parts.append(f'<link name="{link}">{_inertial(_MASSES[i])}{_joint_disk(_RADII[i])}'
                     f'{_segment(x_next, z_next, _RADII[i] * 0.8, "ur_grey")}</link>')
        parts.append(f'<joint name={quoteattr(names[i])} type="revolute"><parent link="{parent}"/><child link="{link}"/>'
                     f'<origin xyz="{origin[0]:.6f} 0 {origin[1]:.6f}" rpy="{origin[2]:.9f} 0 0"/>'
                     f'<axis xyz="0 0 1"/><limit lower="{-kin.JOINT_LIMIT:.6f}" upper="{kin.JOINT_LIMIT:.6f}" '
                     f'effort="330" velocity="3.15"/><dynamics damping="0.0" friction="0.0"/></joint>')
        parent, origin = link, (x_next, z_next, kin.ALPHA[i])
    # Flange = DH frame 6 (UR tool0): fixed offset from link_6.
    parts.append(f'<link name="flange">{_inertial(0.01, 0.01)}</link>')
    parts.append(f'<joint name="flange_joint" type="fixed"><parent link="link_6"/><child link="flange"/>'
                 f'<origin xyz="{origin[0]:.6f} 0 {origin[1]:.6f}" rpy="{origin[2]:.9f} 0 0"/></joint>')
    # F/T sensor: its own link on a fixed joint, so the joint's reaction wrench is the sensor reading.
    ft_geo = f'<geometry><cylinder radius="0.035" length="{FT_LENGTH}"/></geometry>'
    parts.append(f'<link name="ft_sensor">{_inertial(0.2)}'
                 f'<visual><origin xyz="0 0 {FT_LENGTH / 2}"/>{ft_geo}<material name="dark"/></visual>'
                 f'<collision><origin xyz="0 0 {FT_LENGTH / 2}"/>{ft_geo}</collision></link>')
    parts.append(f'<joint name="{FT_JOINT}" type="fixed"><parent link="flange"/><child link="ft_sensor"/>'
                 f'<origin xyz="0 0 0"/></joint>')
    if tool == "vacuum":
        _vacuum_tool(parts)
    else:
        _gripper(parts)
    parts.append('</robot>')
    return "\n".join(parts)


def _gripper(parts: list[str]) -> None:
    body_geo = f'<geometry><box size="0.05 {2 * FINGER_TRAVEL + 2 * FINGER_THICK + 0.02:.4f} {GRIPPER_BASE}"/></geometry>'
    parts.append(f'<link name="gripper_body">{_inertial(0.6)}'
                 f'<visual><origin xyz="0 0 {GRIPPER_BASE / 2}"/>{body_geo}<material name="ur_grey"/></visual>'
                 f'<collision><origin xyz="0 0 {GRIPPER_BASE / 2}"/>{body_geo}</collision></link>')
    parts.append(f'<joint name="gripper_mount" type="fixed"><parent link="ft_sensor"/><child link="gripper_body"/>'
                 f'<origin xyz="0 0 {FT_LENGTH}"/></joint>')
    # Fingers: prismatic along +y (left) / -y (right); joint value = inner face distance from the centre.
    f_geo = f'<geometry><box size="{FINGER_WIDTH} {FINGER_THICK} {FINGER_LENGTH}"/></geometry>'
    for name, sign in (("finger_left", 1), ("finger_right", -1)):
        org = f'<origin xyz="0 {sign * FINGER_THICK / 2:.4f} {FINGER_LENGTH / 2}"/>'
        mat = "pad" if name == TACTILE_LINK else "dark"
        parts.append(f'<link name="{name}">{_inertial(0.05, 0.03)}<visual>{org}{f_geo}<material name="{mat}"/></visual>'
                     f'<collision>{org}{f_geo}</collision></link>')
        parts.append(f'<joint name="{name}_joint" type="prismatic"><parent link="gripper_body"/><child link="{name}"/>'
                     f'<origin xyz="0 0 {GRIPPER_BASE}"/><axis xyz="0 {sign} 0"/>'
                     f'<limit lower="0" upper="{FINGER_TRAVEL}" effort="60" velocity="0.15"/></joint>')


def _vacuum_tool(parts: list[str]) -> None:
    body_geo = f'<geometry><cylinder radius="{VACUUM_BODY_RADIUS}" length="{VACUUM_BODY_LENGTH}"/></geometry>'
    parts.append(f'<link name="vacuum_body">{_inertial(0.4)}'
                 f'<visual><origin xyz="0 0 {VACUUM_BODY_LENGTH / 2}"/>{body_geo}<material name="ur_grey"/></visual>'
                 f'<collision><origin xyz="0 0 {VACUUM_BODY_LENGTH / 2}"/>{body_geo}</collision></link>')
    parts.append(f'<joint name="vacuum_mount" type="fixed"><parent link="ft_sensor"/><child link="vacuum_body"/>'
                 f'<origin xyz="0 0 {FT_LENGTH}"/></joint>')
    cup_geo = f'<geometry><cylinder radius="{CUP_RADIUS}" length="{CUP_LENGTH}"/></geometry>'
    parts.append(f'<link name="{CUP_LINK}">{_inertial(0.05, 0.02)}'
                 f'<visual><origin xyz="0 0 {-CUP_LENGTH / 2}"/>{cup_geo}<material name="pad"/></visual>'
                 f'<collision><origin xyz="0 0 {-CUP_LENGTH / 2}"/>{cup_geo}</collision></link>')
    parts.append(f'<joint name="cup_mount" type="fixed"><parent link="vacuum_body"/><child link="{CUP_LINK}"/>'
                 f'<origin xyz="0 0 {VACUUM_BODY_LENGTH + CUP_LENGTH}"/></joint>')


def write_urdf(directory: Optional[str] = None, tool: str = "gripper") -> str:
    """Write the generated URDF of an arm with `tool` to a file (PyBullet loads files) and return its path."""
    directory = directory or tempfile.mkdtemp(prefix="sim-urdf-")
    path = os.path.join(directory, f"ur5_{tool}.urdf")
    if not os.path.exists(path):
        with open(path, "w") as fh:
            fh.write(urdf_text(tool))
    return path
