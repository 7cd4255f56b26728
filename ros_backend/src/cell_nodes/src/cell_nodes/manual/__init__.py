"""Manual motion (feature `manual`): the robot driver's logic in plain Python, tested without ROS.

- config: the cell file's `manual:` section (groups, named configurations, tools and their step sequences), each
  group's controller host (resolve_hosts: UR_HOSTS, groups[].host, UR_HOST) and the arms (plan_arms: groups by host)
- limits: speed/acceleration defaults and caps (the TCP never above 0.25 m/s in manual motion)
- frames: rotation vectors, poses, relative offsets and jog twists in the base or the tool frame
- jog: the hold-to-run supervisor (heartbeat timeout, stop on direction 0, replace, never queue)
- controller: the ur_rtde interfaces behind a small protocol, and the gate every call goes through
- driver: moves (and their preview: one target computation, move_target), jogs, tool actions, stop, state and
  reconnection of one arm against that protocol
- cell_driver: one driver per arm; routes requests by group (tools by their group), stops every arm, state per group

The rospy node (cell_nodes/scripts/manual_node) only wires these to topics and services.
"""
