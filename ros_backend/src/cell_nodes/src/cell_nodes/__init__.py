"""The cell UI's own ROS nodes; each node's logic lives in a module that does not import rospy."""
