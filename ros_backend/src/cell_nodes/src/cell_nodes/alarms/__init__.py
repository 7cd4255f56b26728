"""Alarms (feature `alarms`): the cell's alarm list and safety status, in plain Python, tested without ROS.

- config: the cell file's `alarms:` section (force limit, wrench and fault topics, timeouts, severity overrides)
  and what the node needs from the rest of the file (operation mode names, WrenchStamped sensors)
- table: the alarm table: sources report what they detect now; alarms become active, inactive (gone, not reset),
  and leave the list on reset; first seen, last seen, how often
- sources: what each source turns into conditions (the robot driver's state, device fault lists, the wrist force,
  module states), and the silence watch for sources that stop publishing
- status: the overall status (normal, warning, fault, safeguard stop, protective stop, emergency stop)
- mode: when to switch the operation mode to `alarm` and back
- core: all of these together, driven by the node's callbacks with explicit timestamps

The rospy node (cell_nodes/scripts/alarms_node) only wires these to topics and services.
"""
