"""A simulated ros_control robot cell (KUKA LBR iiwa from pybullet_data with a vacuum cup).

It stands for the robot's ros_control driver (iiwa_stack): a joint_trajectory_controller (action + command topic),
/joint_states, robot_description and the tool's IO over ROS. See docs/sim.md, "The ros_control cell".
- spec.py: the cell file's `simulation:` section (kind: ros_control) and the arm's ROS names from manual.groups
- trajectory.py: the joint_trajectory_controller logic, plain Python (tested without ROS)
- model.py: the URDF as simulated (renamed names, the tool with a fixed link at the cup face)
- world.py: the PyBullet world (reuses sim/world.py's table, parts, fixtures and vacuum)
- cell.py: the 500 Hz loop, faults, wiring; driver.py: the rospy layer; main.py: the CLI
"""
