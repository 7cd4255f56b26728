"""The static TF the 3D view reads (the cell file's `scene.fixed_frame` and `scene.arms[].base_frame`).

On a real cell a static_transform_publisher (or the cell's URDF through robot_state_publisher) says where each arm's
base stands in the cell frame; the sim says it from where it placed the arm (simulation.arms[].base), latched on
/tf_static as tf2_msgs/TFMessage, so the view places the arm from TF the same way here as there.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from .cell_file import SceneSpec
from .scene import WorldSpec

TF_STATIC = "/tf_static"


@dataclass(frozen=True)
class StaticFrame:
    parent: str
    child: str
    translation: tuple[float, float, float]
    rotation: tuple[float, float, float, float]      # quaternion x, y, z, w


def base_frames(scene: SceneSpec, world: WorldSpec) -> list[StaticFrame]:
    """fixed_frame -> base_frame of every scene arm that names one and is a simulated arm (others: not ours to say)."""
    if scene.fixed_frame is None:
        return []
    out = []
    for arm in scene.arms:
        if arm.base_frame is None:
            continue
        try:
            sim_arm = world.arm(arm.group)
        except KeyError:
            continue
        half = sim_arm.yaw / 2.0
        out.append(StaticFrame(scene.fixed_frame, arm.base_frame, tuple(float(v) for v in sim_arm.base),  # type: ignore[arg-type]
                               (0.0, 0.0, math.sin(half), math.cos(half))))
    return out


def tf_message(frames: list[StaticFrame], stamp: Any, types: Any) -> Any:
    """The frames as one tf2_msgs/TFMessage; `types` has TFMessage and TransformStamped (the rospy classes)."""
    out = types.TFMessage()
    for f in frames:
        t = types.TransformStamped()
        t.header.stamp = stamp
        t.header.frame_id = f.parent
        t.child_frame_id = f.child
        t.transform.translation.x, t.transform.translation.y, t.transform.translation.z = f.translation
        r = t.transform.rotation
        r.x, r.y, r.z, r.w = f.rotation
        out.transforms.append(t)
    return out
