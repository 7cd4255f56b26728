"""The video feature's ROS side: raw camera images (sensor_msgs/Image) as JPEG sized to each viewer."""
