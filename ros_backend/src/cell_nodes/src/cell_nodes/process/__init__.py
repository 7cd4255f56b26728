"""Automatic process (feature `process`): the cell file's operations run step by step through the robot driver.

- config: the cell file's `process:` section (operations, steps, pose tables, defaults), checked with clear errors
- steps: each step's text for the page and the log, and where a pose step goes in a given cycle
- conditions: a wait_topic step's field path and comparison
- executor: the run (sequencing, cycling, pause at a step's end, resume, stop at once, dry run, errors)
- mode: the operation mode following the process (never out of `alarm`)
- client: the UI's side (refusals, the published state from the server's feedback, the cycle counter, the log)

The rospy nodes (cell_nodes/scripts/process_server: the action server; process_node: the client and the UI's
services and topics) only wire these to ROS. See docs/ros-interfaces.md.
"""
