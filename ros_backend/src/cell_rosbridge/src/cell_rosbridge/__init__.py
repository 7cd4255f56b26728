"""cell_rosbridge: our rosbridge v2 server for ROS 1 (protocol library + thin transports)."""
