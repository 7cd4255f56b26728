"""The tornado transport in-process: TCP_NODELAY, text/binary frame kinds, disconnect releases."""
from __future__ import annotations

import asyncio
import socket
import threading
from typing import Any, Iterator, Set

import pytest
import tornado.httpserver
import tornado.ioloop
import tornado.netutil

from cell_rosbridge.node import build_context
from cell_rosbridge.websocket_server import Janitor, RosbridgeHandler, make_app
from rb_helpers import wait_for
from rb_wsclient import WSClient


class InProcessServer:
    def __init__(self) -> None:
        self.context = build_context()
        self.clients: Set[RosbridgeHandler] = set()
        self.janitor = Janitor()
        sockets = tornado.netutil.bind_sockets(0, "127.0.0.1")
        self.port = sockets[0].getsockname()[1]
        started = threading.Event()

        def run() -> None:
            asyncio.set_event_loop(asyncio.new_event_loop())
            self.loop = tornado.ioloop.IOLoop.current()
            server = tornado.httpserver.HTTPServer(make_app(self.context, self.clients, self.janitor, 1 << 20))
            server.add_sockets(sockets)
            started.set()
            self.loop.start()
            server.stop()

        self.thread = threading.Thread(target=run, daemon=True)
        self.thread.start()
        started.wait(5)

    def stop(self) -> None:
        self.loop.add_callback(self.loop.stop)
        self.thread.join(5)
        self.janitor.stop()
        self.context.hub.shutdown()
        self.context.publishers.shutdown()


@pytest.fixture
def server(ros_node: str) -> Iterator[InProcessServer]:
    s = InProcessServer()
    yield s
    s.stop()


def test_tcp_nodelay_is_set_on_every_connection(server: InProcessServer) -> None:
    c = WSClient(server.port)
    wait_for(lambda: len(server.clients) == 1, 5, what="connection registered")
    handler = next(iter(server.clients))
    sock = handler.ws_connection.stream.socket
    assert sock.getsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY) == 1
    c.close()
    wait_for(lambda: not server.clients, 5, what="connection closed")


def test_cbor_replies_are_binary_and_json_replies_text(server: InProcessServer) -> None:
    c = WSClient(server.port)
    c.send_json({"op": "call_service", "id": 1, "service": "/tp_missing", "compression": "cbor"})
    opcode, _ = c.recv_frame()
    assert opcode == 2
    c.send_json({"op": "call_service", "id": 2, "service": "/tp_missing"})
    opcode, _ = c.recv_frame()
    assert opcode == 1
    c.close()


def test_disconnect_releases_everything(server: InProcessServer) -> None:
    c = WSClient(server.port)
    c.send_json({"op": "subscribe", "topic": "/tp_sub", "type": "std_msgs/String"})
    c.send_json({"op": "advertise", "topic": "/tp_pub", "type": "std_msgs/String"})
    c.send_json({"op": "advertise_service", "service": "/tp_srv", "type": "std_srvs/Trigger"})
    c.send_json({"op": "nope", "id": "sync"})  # ops are handled in order: this reply means all are done
    c.recv_until(lambda m: m.get("id") == "sync")
    assert server.context.hub.count() == 1 and server.context.publishers.count() == 1
    assert "/tp_srv" in server.context.services
    c.close()
    wait_for(lambda: server.context.hub.count() == 0 and server.context.publishers.count() == 0
             and not server.context.services, 10, what="resources released")
