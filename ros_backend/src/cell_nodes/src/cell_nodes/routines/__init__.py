"""Routines (feature 8): teach and replay. Poses and tool actions are recorded into a draft kept by the page, saved
as one JSON file per routine, and run through the robot driver (/cell/manual/). Plain Python here (config, names
and files, the runner, the log); scripts/routines_node wires it to ROS."""
