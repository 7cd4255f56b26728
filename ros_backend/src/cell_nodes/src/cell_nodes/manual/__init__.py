"""Manual motion (feature `manual`): the robot driver's logic in plain Python, tested without ROS.

- config: the cell file's `manual:` section (groups, named configurations, tools and their step sequences)
- limits: speed/acceleration defaults and caps (the TCP never above 0.25 m/s in manual motion)
- frames: rotation vectors, poses, relative offsets and jog twists in the base or the tool frame
- jog: the hold-to-run supervisor (heartbeat timeout, stop on direction 0, replace, never queue)
- controller: the ur_rtde interfaces behind a small protocol, and the gate every call goes through
- driver: moves, jogs, tool actions, stop, state and reconnection against that protocol

The rospy node (cell_nodes/scripts/manual_node) only wires these to topics and services.
"""
