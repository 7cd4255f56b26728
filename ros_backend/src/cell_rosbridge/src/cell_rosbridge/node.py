"""The rosbridge_server node: parameters, ROS init, tornado loop, clean shutdown."""
from __future__ import annotations

import faulthandler
import logging
import os
import signal
import sys
from typing import Any, Optional, Set

import rospy
import tornado.ioloop

from . import capabilities
from .protocol import BridgeConfig, BridgeContext
from .ros_plumbing import publish_without_yield
from .websocket_server import Janitor, RosbridgeHandler, make_app

log = logging.getLogger("rosbridge")


def _param(name: str, default: Any) -> Any:
    value = rospy.get_param(name, default)
    return type(default)(value) if default is not None else value


def build_context(config: Optional[BridgeConfig] = None) -> BridgeContext:
    """The shared server state with every rosbridge op registered (the dispatcher imports no op)."""
    context = BridgeContext(config=config or BridgeConfig())
    capabilities.register_all(context)
    return context


def main(argv: Any = None) -> None:
    # Our own signal handling: rospy's handler runs hooks inside the signal frame, where tornado's
    # add_callback does not wake the loop (it thinks it is on the loop thread), so SIGINT would hang.
    rospy.init_node("rosbridge_websocket", argv=argv, disable_signals=True)
    # `kill -USR1 <pid>`: every thread's Python stack on stderr (a stalled loop shows what it waits for).
    faulthandler.register(signal.SIGUSR1, all_threads=True)
    publish_without_yield()  # publishes run on the loop thread (see there)
    # rospy already configured the root logger (ROS log file); also show our own lines on stderr,
    # where roslaunch output="screen" and process supervisors pick them up.
    handler = logging.StreamHandler(sys.stderr)
    handler.setFormatter(logging.Formatter("[rosbridge] %(levelname)s %(message)s"))
    log.addHandler(handler)
    log.setLevel(logging.INFO)
    logging.getLogger("tornado.access").setLevel(logging.WARNING)  # one line per connection is noise
    port = _param("~port", int(os.environ.get("ROSBRIDGE_PORT", "9090")))
    address = _param("~address", "127.0.0.1")
    cfg = BridgeConfig(
        max_message_size=_param("~max_message_size", BridgeConfig.max_message_size),
        max_client_buffer=_param("~max_client_buffer", BridgeConfig.max_client_buffer),
        default_queue_length=_param("~default_queue_length", BridgeConfig.default_queue_length),
        service_request_timeout=_param("~service_request_timeout", BridgeConfig.service_request_timeout),
        publisher_replay_window=_param("~publisher_replay_window", BridgeConfig.publisher_replay_window),
        publisher_replay_max=_param("~publisher_replay_max", BridgeConfig.publisher_replay_max),
        unregister_timeout=_param("~unregister_timeout", BridgeConfig.unregister_timeout),
    )
    context = build_context(cfg)
    clients: Set[RosbridgeHandler] = set()
    loop = tornado.ioloop.IOLoop.current()
    janitor = Janitor()
    app = make_app(context, clients, janitor, hard_limit=max(cfg.max_message_size * 4, 1 << 20))
    server = app.listen(port, address=address)
    rospy.loginfo("rosbridge v2 WebSocket server on ws://%s:%d", address, port)
    print(f"rosbridge listening on {address}:{port}", flush=True)

    def stop() -> None:
        server.stop()
        for handler in list(clients):
            handler.close(1001, "server shutting down")
        loop.stop()

    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, lambda *_: loop.add_callback_from_signal(stop))
    try:
        loop.start()
    finally:
        janitor.stop()
        context.hub.shutdown()
        context.publishers.shutdown()
        for svc in list(context.services.values()):
            svc.shutdown("server shutting down")
        if not rospy.is_shutdown():
            rospy.signal_shutdown("rosbridge stopped")
