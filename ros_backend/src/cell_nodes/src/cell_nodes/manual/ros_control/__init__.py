"""The `ros_control` motion backend: an arm driven through a joint_trajectory_controller (FollowJointTrajectory
action and its command topic) instead of a UR controller; kinematics (KDL, from the robot_description URDF) and
trajectory building here, so the driver core sees the same controller protocol as with ur_rtde.
"""
