"""The server's run loop, the same for both generations: the shared context with every op, the WebSocket app on
tornado, signals, and the release of every ROS resource at the end. node.py (rospy) and node_ros2.py (rclpy)
only read their parameters and start their ROS client library."""
from __future__ import annotations

import faulthandler
import logging
import signal
import sys
from typing import Callable, Optional, Set

import tornado.ioloop

from . import capabilities
from .protocol import BridgeConfig, BridgeContext
from .websocket_server import Janitor, RosbridgeHandler, make_app

log = logging.getLogger("rosbridge")


def build_context(config: Optional[BridgeConfig] = None) -> BridgeContext:
    """The shared server state with every rosbridge op registered (the dispatcher imports no op)."""
    context = BridgeContext(config=config or BridgeConfig())
    capabilities.register_all(context)
    return context


def log_to_stderr() -> None:
    """Our own lines on stderr, where launchers and process supervisors pick them up."""
    handler = logging.StreamHandler(sys.stderr)
    handler.setFormatter(logging.Formatter("[rosbridge] %(levelname)s %(message)s"))
    log.addHandler(handler)
    log.setLevel(logging.INFO)
    logging.getLogger("tornado.access").setLevel(logging.WARNING)  # one line per connection is noise


def run(cfg: BridgeConfig, port: int, address: str, announce: Callable[[str], None]) -> None:
    """Serve until SIGINT or SIGTERM; then close every client and release every ROS resource."""
    # `kill -USR1 <pid>`: every thread's Python stack on stderr (a stalled loop shows what it waits for).
    faulthandler.register(signal.SIGUSR1, all_threads=True)
    context = build_context(cfg)
    clients: Set[RosbridgeHandler] = set()
    loop = tornado.ioloop.IOLoop.current()
    janitor = Janitor()
    app = make_app(context, clients, janitor, hard_limit=max(cfg.max_message_size * 4, 1 << 20))
    server = app.listen(port, address=address)
    announce(f"rosbridge v2 WebSocket server on ws://{address}:{port}")
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
