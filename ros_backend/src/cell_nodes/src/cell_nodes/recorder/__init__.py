"""The flight recorder (issue 30): the last seconds of the cell's topics in memory, saved as MCAP around an alarm.

ring.py keeps the raw messages (bounded in seconds and bytes), mcap_file.py writes a window of them as an MCAP file
with the ROS 1 definitions embedded, retention.py keeps the recordings directory within its count and bytes. No ROS
here: the node hands in serialized messages with their type, md5sum and definition (what rospy.AnyMsg carries).
"""
