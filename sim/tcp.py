"""A small threaded TCP server base: bind one host:port, one thread per client, never crash on a client."""
from __future__ import annotations

import logging
import socket
import threading
from typing import Optional

log = logging.getLogger("sim.tcp")


class TcpServer:
    def __init__(self, host: str, port: int, name: str) -> None:
        self.host, self.port, self.name = host, port, name
        self._stop = threading.Event()
        self._sock: Optional[socket.socket] = None
        self._thread: Optional[threading.Thread] = None
        self._clients: set[socket.socket] = set()
        self._lock = threading.Lock()

    def stopping(self) -> bool:
        return self._stop.is_set()

    def start(self) -> None:
        s = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        s.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        s.bind((self.host, self.port))
        s.listen(16)
        s.settimeout(0.1)  # so the accept loop notices stop() quickly
        self._sock = s
        self._thread = threading.Thread(target=self._accept_loop, name=f"{self.name}-accept", daemon=True)
        self._thread.start()
        log.info("%s listening on %s:%d", self.name, self.host, self.port)

    def _accept_loop(self) -> None:
        assert self._sock is not None
        while not self._stop.is_set():
            try:
                client, addr = self._sock.accept()
            except socket.timeout:
                continue
            except OSError:
                break
            client.settimeout(None)
            with self._lock:
                self._clients.add(client)
            threading.Thread(target=self._serve, args=(client, addr), name=f"{self.name}-{addr[1]}",
                             daemon=True).start()

    def _serve(self, client: socket.socket, addr) -> None:
        try:
            self.handle(client)
        except (ConnectionError, OSError) as e:
            if not self._stop.is_set():
                log.info("%s client %s:%d disconnected: %s", self.name, addr[0], addr[1], e)
        except Exception:  # a bad client must never take the server down
            log.exception("%s client %s:%d: handler error", self.name, addr[0], addr[1])
        finally:
            with self._lock:
                self._clients.discard(client)
            try:
                client.close()
            except OSError:
                pass

    def handle(self, client: socket.socket) -> None:
        raise NotImplementedError

    def signal_stop(self) -> None:
        """First phase of stopping: flag it so every server's loops wind down in parallel."""
        self._stop.set()

    def stop(self) -> None:
        self._stop.set()
        if self._sock is not None:
            self._sock.close()
        with self._lock:
            clients = list(self._clients)
        for c in clients:
            try:
                c.shutdown(socket.SHUT_RDWR)
            except OSError:
                pass
        if self._thread is not None:
            self._thread.join(1.0)
