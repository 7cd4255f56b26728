"""rosapi under a stream of calls: each call is served on a new thread; nothing may be left behind per call."""
from __future__ import annotations

import subprocess
from pathlib import Path


def test_calls_leave_no_socket_to_the_garbage_collector(ros_node: str, rosapi: subprocess.Popen) -> None:
    """A master proxy per service thread left each thread's socket unclosed: its ResourceWarning text, unique per
    port, piled up in a warnings registry (~250 B per call, rosapi's steady RSS growth in the soak)."""
    import rospy
    from rosapi import srv

    calls = [("/rosapi/topics", srv.Topics, ()), ("/rosapi/services", srv.Services, ()),
             ("/rosapi/nodes", srv.Nodes, ()), ("/rosapi/service_type", srv.ServiceType, ("/rosapi/topics",)),
             ("/rosapi/node_details", srv.NodeDetails, ("/rosapi",)), ("/rosapi/publishers", srv.Publishers,
                                                                       ("/rosout",))]
    for i in range(120):
        name, cls, args = calls[i % len(calls)]
        answer = rospy.ServiceProxy(name, cls)(*args)  # a new connection each time: a new thread in rosapi
        assert answer is not None
    assert "/rosapi/topics" in rospy.ServiceProxy("/rosapi/services", srv.Services)().services
    log = Path(rosapi.stderr_path).read_text()  # type: ignore[attr-defined]
    assert log.count("unclosed") == 0, log[-2000:]
