"""WebSocket transport (tornado): a thin shell that moves frames between sockets and protocol.Client."""
from __future__ import annotations

import queue
import threading
import logging
import socket
import time
from typing import Any, Optional, Set

import tornado.ioloop
import tornado.web
import tornado.websocket

from .encoding import Frame
from .outbox import ClientOutbox
from .protocol import BridgeContext, Client

log = logging.getLogger("rosbridge")


class Janitor:
    """One long-lived thread that releases disconnected clients' ROS resources.

    Why: unregistering subscribers/publishers/services does master XMLRPC; doing it on the event loop
    would stall every other client, and a thread pool would grow/shrink the thread count unpredictably.
    """

    def __init__(self) -> None:
        self._queue: "queue.Queue[Optional[Client]]" = queue.Queue()
        self._thread = threading.Thread(target=self._run, name="rosbridge-janitor", daemon=True)
        self._thread.start()

    def release(self, client: Client) -> None:
        self._queue.put(client)

    def _run(self) -> None:
        while True:
            client = self._queue.get()
            if client is None:
                return
            try:
                client.finish()
            except Exception:
                log.exception("cleanup of %s failed", client.name)

    def stop(self, timeout: float = 5.0) -> None:
        self._queue.put(None)
        self._thread.join(timeout)


class RosbridgeHandler(tornado.websocket.WebSocketHandler):
    context: BridgeContext
    clients: Set["RosbridgeHandler"]

    def initialize(self, context: BridgeContext, clients: Set["RosbridgeHandler"], janitor: Janitor) -> None:
        self.context = context
        self.janitor = janitor
        self.clients = clients
        self.loop = tornado.ioloop.IOLoop.current()
        self.client: Optional[Client] = None
        self._pumping = False
        self._timer: Optional[object] = None

    def check_origin(self, origin: str) -> bool:
        # We bind to loopback only; the BFF in front of us does authentication and origin checks.
        return True

    def open(self, *args: Any, **kwargs: Any) -> None:
        self.set_nodelay(True)  # small frames (status, joint states) must not wait for Nagle
        cfg = self.context.config
        outbox = ClientOutbox(cfg.max_client_buffer, cfg.default_queue_length,
                              wakeup=lambda: self.loop.add_callback(self._kick),
                              on_overflow=lambda reason: self.loop.add_callback(self._overflow, reason))
        peer = self.request.remote_ip
        self.client = Client(self.context, outbox, name=f"client {peer}")
        self.client.name = f"client{self.client.id}@{peer}"
        self.clients.add(self)
        log.info("%s connected (%d clients)", self.client.name, len(self.clients))

    def on_message(self, message: Frame) -> None:
        if self.client is not None:
            self.client.incoming(message)

    def on_close(self) -> None:
        self.clients.discard(self)
        if self.client is not None:
            log.info("%s disconnected (%d clients)", self.client.name, len(self.clients))
            client, self.client = self.client, None
            client.outbox.close()
            self.janitor.release(client)

    def _overflow(self, reason: str) -> None:
        if self.client is not None:
            log.warning("%s disconnected: %s", self.client.name, reason)
            self.close(1008, reason[:120])
            self.on_close()

    def _kick(self) -> None:
        if self._pumping or self.client is None:
            return
        self._pumping = True
        self.loop.spawn_callback(self._pump)

    async def _pump(self) -> None:
        """Drain the outbox; awaiting each write is the backpressure that lets the outbox drop/cap."""
        try:
            while self.client is not None:
                frames, delay = self.client.outbox.pop(time.monotonic())
                if frames is None:
                    if delay is not None:
                        self.loop.call_later(delay, self._kick)
                    return
                for frame in frames:
                    await self.write_message(frame, binary=isinstance(frame, bytes))
        except tornado.websocket.WebSocketClosedError:
            pass
        except tornado.iostream.StreamClosedError:
            pass
        finally:
            self._pumping = False


def make_app(context: BridgeContext, clients: Set[RosbridgeHandler], janitor: Janitor,
             hard_limit: int) -> tornado.web.Application:
    return tornado.web.Application(
        [(r"/.*", RosbridgeHandler, {"context": context, "clients": clients, "janitor": janitor})],
        # Frames above the configured max get a status error from the protocol; only frames far above
        # it are refused by tornado itself (connection closed with 1009).
        websocket_max_message_size=hard_limit,
        websocket_ping_interval=None,
    )

