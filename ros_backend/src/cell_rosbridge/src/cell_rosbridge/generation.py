"""Which ROS generation this process talks to: ROS_VERSION, as both generations' setup scripts export it (1 if unset).

Only the plumbing (plumbing.py) and the message types (conversion.py) ask; op handling never does. One process
runs one generation: ROS 1's genpy and ROS 2's rosidl make Python packages of the same names.
"""
from __future__ import annotations

import os

ROS_VERSION: int = 2 if os.environ.get("ROS_VERSION", "1").strip() == "2" else 1
