"""Modules (feature `modules`): launch and stop groups of launch files and watch their state. Plain Python,
tested without ROS (rospy is never imported here; roslaunch, rospkg and the master's XML-RPC API only inside the
classes that need them).

- config: the cell file's `modules:` section (names, launch file references, node names, timeouts), and the
  resolution of a `package/relative/path.launch` reference to a file inside that package
- state: the per-module state machine (active / inactive / transitioning / incomplete) from node liveness
- launcher: the launcher abstraction and its roslaunch implementation (one ROSLaunchParent per module, output
  captured to per-node log files)
- graph: node liveness from the ROS master (bounded, parallel pings; dead nodes are cleaned from the master)
- output: the bounded per-node buffer of /rosout lines (the output of modules the launcher did not start)
- manager: launch/stop/output requests, the worker threads, the one-second poll
- demo: the computations of the demo cell's module nodes (vision brightness, vision status)

The rospy node (cell_nodes/scripts/modules_node) only wires these to the topic and the services.
"""
