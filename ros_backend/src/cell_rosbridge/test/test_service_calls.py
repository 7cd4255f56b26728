"""The server under a stream of call_service ops: nothing may be left behind per call."""
from __future__ import annotations

import subprocess
from typing import Any, Callable

from rb_helpers import BridgeProcess
from rb_wsclient import WSClient


def test_service_calls_leave_no_socket_to_the_garbage_collector(make_bridge: Callable[..., BridgeProcess],
                                                                rosapi: subprocess.Popen) -> None:
    """rosservice.get_service_type and rospy.ServiceProxy each made a master proxy per call and left its socket to
    the garbage collector: the "unclosed socket" ResourceWarning text, unique per port, piled up in a warnings
    registry, ~250 B per call (the soak's 1,500 calls a minute: rosbridge's +0.36 MiB a minute)."""
    b = make_bridge(env={"PYTHONWARNINGS": "always::ResourceWarning"})
    c = WSClient(b.port)
    try:
        for i in range(120):
            c.send_json({"op": "call_service", "id": f"c{i}", "service": "/rosapi/topics"})
            resp: Any = c.recv_until(lambda m, i=i: m.get("id") == f"c{i}", 10)
            assert resp["result"] is True, resp
        c.send_json({"op": "call_service", "id": "gone", "service": "/no/such/service"})
        assert c.recv_until(lambda m: m.get("id") == "gone", 10)["result"] is False
    finally:
        c.close()
    assert b.log().count("unclosed") == 0, b.log()[-2000:]
