"""The sim stands for the robot's own controller: it claims the motion path's priority (cell_nodes.priority, docs/service.md
"Priorities") when that module is on the path (the ROS environment); the sim alone (--no-ros, outside it) runs at
normal priority and says so."""
from __future__ import annotations


def claim_priority(what: str) -> str:
    try:
        from cell_nodes import priority
    except ImportError:
        return f"{what}: normal priority (cell_nodes.priority is not on the path: source scripts/ros-env.sh)"
    return priority.claim(priority.MOTION, what)
