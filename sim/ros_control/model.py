"""The arm's URDF as simulated: a pybullet_data model with its names renamed (e.g. lbr_iiwa_ -> iiwa_, as iiwa_stack
publishes them) and the vacuum tool added on the flange.

Tool: a fixed joint `<prefix>joint_ft` on the flange carries the wrist F/T reading (its reaction wrench) and the
tool body; a fixed joint `<prefix>joint_ee` puts the tip link (the cell file's tip_link, e.g. iiwa_link_ee) at the
cup's face, z out of the cup. The same text (mesh paths as file:// URIs) is the robot_description parameter.
"""
from __future__ import annotations

import os
import re
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from typing import Mapping

import pybullet_data

# The flange sits this far along the last link's z axis from its origin (the model has no flange link): the
# pybullet_data iiwa has the LBR's 0.126 m from joint 6 to the flange = 0.081 (joint 7) + 0.045.
FLANGE_OFFSETS = {"kuka_iiwa/model.urdf": 0.045}
CUP_LENGTH = 0.02
CUP_RADIUS = 0.016
FT_LENGTH = 0.015
BODY_RADIUS = 0.03
TOOL_MASS = 0.4


class ModelError(ValueError):
    """The model cannot be used (missing, not a serial chain of revolute joints)."""


@dataclass(frozen=True)
class JointInfo:
    name: str          # renamed
    lower: float
    upper: float
    velocity: float
    effort: float


@dataclass(frozen=True)
class ArmModel:
    path: str                       # the original URDF file
    joints: tuple[JointInfo, ...]   # movable joints, chain order, renamed
    links: tuple[str, ...]          # renamed link names
    base_link: str
    last_link: str
    prefix: str                     # e.g. "iiwa_": for the tool's own joint and link names
    flange_offset: float

    @property
    def joint_names(self) -> tuple[str, ...]:
        return tuple(j.name for j in self.joints)


def model_path(model: str) -> str:
    return os.path.join(pybullet_data.getDataPath(), model)


def _renamer(rename: Mapping[str, str]):
    def apply(name: str) -> str:
        for old, new in rename.items():
            name = name.replace(old, new)
        return name
    return apply


def load_model(model: str, rename: Mapping[str, str]) -> ArmModel:
    path = model_path(model)
    try:
        root = ET.parse(path).getroot()
    except (OSError, ET.ParseError) as e:
        raise ModelError(f"cannot read {model} from pybullet_data: {e}") from None
    ren = _renamer(rename)
    links = [ren(l.get("name", "")) for l in root.findall("link")]
    joints, children = [], set()
    for j in root.findall("joint"):
        children.add(j.find("child").get("link"))
        if j.get("type") in ("revolute", "continuous", "prismatic"):
            lim = j.find("limit")
            get = (lambda k, d: float(lim.get(k, d))) if lim is not None else (lambda k, d: float(d))
            joints.append(JointInfo(ren(j.get("name")), get("lower", 0), get("upper", 0), get("velocity", 0),
                                    get("effort", 0)))
    roots = [l.get("name") for l in root.findall("link") if l.get("name") not in children]
    if not joints or len(roots) != 1:
        raise ModelError(f"{model}: expected one serial chain of movable joints")
    last = [l for l in root.findall("link")][-1].get("name")
    prefix = re.sub(r"joint_?\d+$", "", joints[-1].name)
    return ArmModel(path=path, joints=tuple(joints), links=tuple(links), base_link=ren(roots[0]),
                    last_link=ren(last), prefix=prefix, flange_offset=FLANGE_OFFSETS.get(model, 0.0))


def _inertial(mass: float, z: float = 0.0) -> str:
    i = mass * 0.05 * 0.05 / 6
    return (f'<inertial><origin xyz="0 0 {z:.4f}"/><mass value="{mass}"/>'
            f'<inertia ixx="{i:.6g}" iyy="{i:.6g}" izz="{i:.6g}" ixy="0" ixz="0" iyz="0"/></inertial>')


def _cylinder(radius: float, length: float, z: float, material: str) -> str:
    geo = f'<geometry><cylinder radius="{radius}" length="{length:.4f}"/></geometry>'
    org = f'<origin xyz="0 0 {z:.4f}"/>'
    return f'<visual>{org}{geo}<material name="{material}"/></visual><collision>{org}{geo}</collision>'


def ft_link(model: ArmModel) -> str:
    return f"{model.prefix}link_ft"


def ft_joint(model: ArmModel) -> str:
    return f"{model.prefix}joint_ft"


def urdf_text(model: ArmModel, rename: Mapping[str, str], tip_link: str, tool_length: float,
              mesh_uri: bool = False) -> str:
    """The model's URDF renamed, with the vacuum tool. mesh_uri: file:// URIs (robot_description) instead of the
    absolute paths PyBullet loads."""
    root = ET.parse(model.path).getroot()
    ren = _renamer(rename)
    for el in root.iter():
        if el.tag in ("link", "joint") and el.get("name"):
            el.set("name", ren(el.get("name")))
        if el.tag in ("parent", "child") and el.get("link"):
            el.set("link", ren(el.get("link")))
        if el.tag == "mesh" and el.get("filename") and not os.path.isabs(el.get("filename")):
            absolute = os.path.normpath(os.path.join(os.path.dirname(model.path), el.get("filename")))
            el.set("filename", ("file://" + absolute) if mesh_uri else absolute)
    ET.SubElement(root, "material", name="tool_grey").append(ET.Element("color", rgba="0.7 0.7 0.72 1"))
    ET.SubElement(root, "material", name="cup").append(ET.Element("color", rgba="0.15 0.15 0.15 1"))
    body = tool_length - CUP_LENGTH  # flange .. cup: F/T disk and vacuum body
    tool = (f'<link name="{ft_link(model)}">{_inertial(TOOL_MASS, body / 2)}'
            f'{_cylinder(BODY_RADIUS, body, body / 2, "tool_grey")}</link>'
            f'<joint name="{ft_joint(model)}" type="fixed"><parent link="{model.last_link}"/>'
            f'<child link="{ft_link(model)}"/><origin xyz="0 0 {model.flange_offset}" rpy="0 0 0"/></joint>'
            # The tip link's frame is the cup face (the TCP); the cup lies behind it, inside this link, so the
            # suction's collision filter (this link vs the part) lets a held part touch the face.
            f'<link name="{tip_link}">{_inertial(0.02, -CUP_LENGTH / 2)}'
            f'{_cylinder(CUP_RADIUS, CUP_LENGTH, -CUP_LENGTH / 2, "cup")}</link>'
            f'<joint name="{model.prefix}joint_ee" type="fixed"><parent link="{ft_link(model)}"/>'
            f'<child link="{tip_link}"/><origin xyz="0 0 {tool_length}" rpy="0 0 0"/></joint>')
    for el in ET.fromstring(f"<x>{tool}</x>"):
        root.append(el)
    return '<?xml version="1.0"?>\n' + ET.tostring(root, encoding="unicode")


def write_urdf(directory: str, model: ArmModel, rename: Mapping[str, str], tip_link: str, tool_length: float,
               tag: str = "arm") -> str:
    path = os.path.join(directory, f"ros_control_{tag}.urdf")
    with open(path, "w") as f:
        f.write(urdf_text(model, rename, tip_link, tool_length))
    return path
