"""ur_rtde in a child process, one per connection to a controller: the driver's UR connector.

Why a process: ur_rtde's clients act on threads of their own. When the controller's data pauses for 2.5 s (a
network gap, a loaded host), the control client reconnects on its receive thread, and that reconnect, racing a call
the driver made on another thread, crashed the whole node with SIGSEGV (reproduced by freezing the sim mid-move).
An abandoned control client also keeps reconnecting and takes the controller back from its successor; some calls
hold the GIL while they block, which froze every thread of the node; and the clients' destructors abort the process
after a lost connection. In a child all of that stays in the child: the driver ends it (SIGKILL) when it drops the
connection, and a child that dies is a lost connection, which the driver already handles (it reconnects).

The child runs `python -m cell_nodes.manual.ur_process <fd> <host>` with a socket pair to the parent; requests are
(kind, method, args) on the clients it made (receive, io, control), answered in order. Its stdout and stderr are the
node's: ur_rtde's own messages still reach the node's log.
"""
from __future__ import annotations

import os
import socket
import subprocess
import sys
import threading
from multiprocessing.connection import Connection
from typing import Any, Callable, Optional

from .controller import STATE_GETTERS, CallTimeout, ClientGone, ControlInterface, IOInterface, ReceiveInterface

KINDS = ("receive", "io", "control")


def _methods(protocol: type) -> frozenset[str]:
    return frozenset(n for n in vars(protocol) if not n.startswith("_"))


# The methods a client answers: its interface's (a name outside them is not ur_rtde's, e.g. ros_control's optional
# getMoveError, so hasattr says no), and readState for the receive client.
METHODS = {"receive": _methods(ReceiveInterface) | {"readState"}, "io": _methods(IOInterface),
           "control": _methods(ControlInterface)}
CALL_TIMEOUT_S = 12.0   # a call that takes longer ends the child (the gate gives up on it sooner: see Gate)
START_TIMEOUT_S = 10.0  # the child's imports on a loaded host
CLOSE_TIMEOUT_S = 1.0   # for each client's disconnect when it is dropped cleanly


def make_client(kind: str, host: str) -> Any:
    """The unmodified ur_rtde client of a kind (in the child)."""
    if kind == "receive":
        import rtde_receive
        return rtde_receive.RTDEReceiveInterface(host)
    if kind == "io":
        import rtde_io
        return rtde_io.RTDEIOInterface(host)
    if kind == "control":
        import rtde_control
        # Made without uploading the script: the driver starts it with reuploadScript and waits for it itself, each
        # step bounded (see ManualDriver._control).
        return rtde_control.RTDEControlInterface(host, -1.0, int(rtde_control.RTDEControlInterface.FLAG_NO_WAIT))
    raise ValueError(f"unknown client kind {kind!r}")


def serve(conn: Connection, host: str, make: Callable[[str, str], Any] = make_client) -> None:
    """The child's loop: one request at a time until the parent goes away (or kills it)."""
    clients: dict[str, Any] = {}
    while True:
        try:
            kind, name, args = conn.recv()
        except (EOFError, OSError):
            return
        try:
            if name == "__make__":
                clients[kind] = make(kind, host)
                result: Any = None
            elif name == "readState":
                c = clients[kind]
                result = tuple(getattr(c, g)() for g in STATE_GETTERS)
            else:
                result = getattr(clients[kind], name)(*args)
            reply: tuple[str, Any] = ("ok", result)
        except Exception as e:  # ur_rtde raises RuntimeError with its own text: the parent raises it again
            reply = ("error", f"{e}" or type(e).__name__)
        try:
            conn.send(reply)
        except (EOFError, OSError):
            return


class Link:
    """The parent's end: one child, the clients it holds, calls one at a time, each bounded in time."""

    def __init__(self, host: str) -> None:
        self.host = host
        parent, child = socket.socketpair()
        for end in (parent, child):  # (a default socket timeout, which rospy sets, would make them non-blocking)
            end.setblocking(True)
        try:
            self.proc = subprocess.Popen([sys.executable, "-m", "cell_nodes.manual.ur_process", str(child.fileno()),
                                          host], pass_fds=(child.fileno(),), stdin=subprocess.DEVNULL)
        finally:
            child.close()
        self._conn = Connection(parent.detach())
        self._lock = threading.Lock()
        self._open: set[str] = set()
        self._ended = False

    def call(self, kind: str, name: str, args: tuple = (), timeout: float = CALL_TIMEOUT_S) -> Any:
        with self._lock:
            if self._ended:
                raise ClientGone(f"{name}: the connection to {self.host} was closed")
            try:
                self._conn.send((kind, name, args))
                if not self._conn.poll(timeout):
                    self.kill()
                    raise CallTimeout(f"{name}: no answer within {timeout:g} s")
                status, value = self._conn.recv()
            except (EOFError, OSError):
                self.kill()
                raise RuntimeError(f"the ur_rtde process for {self.host} ended (exit code {self.proc.poll()})") \
                    from None
        if status == "error":
            raise RuntimeError(value)
        return value

    def make(self, kind: str, timeout: float) -> "Client":
        self.call(kind, "__make__", (), timeout)
        self._open.add(kind)
        return Client(self, kind)

    def release(self, kind: str) -> None:
        """A client is dropped: disconnect it (bounded); the last one ends the child."""
        if kind in self._open and not self._ended:
            try:
                self.call(kind, "disconnect", (), CLOSE_TIMEOUT_S)
            except Exception:
                pass  # (a lost connection's disconnect may fail or hang: the child ends below either way)
        self._open.discard(kind)
        if not self._open:
            self.kill()

    def kill(self) -> None:
        """End the child now (a call waiting on it returns with an error); safe from any thread, more than once."""
        self._ended = True
        if self.proc.poll() is None:
            self.proc.kill()
        # Reaped by a thread: wait() returns at once after SIGKILL, unless the host is very busy.
        threading.Thread(target=self.proc.wait, name="ur-reap", daemon=True).start()

    @property
    def alive(self) -> bool:
        return not self._ended and self.proc.poll() is None


class Client:
    """One ur_rtde client in the child, with its methods' names (the driver's Receive/IO/ControlInterface)."""

    def __init__(self, link: Link, kind: str) -> None:
        self._link = link
        self._kind = kind

    def __getattr__(self, name: str) -> Callable[..., Any]:
        if name not in METHODS[self._kind]:
            raise AttributeError(name)
        return lambda *args: self._link.call(self._kind, name, args)

    def disconnect(self) -> None:
        self._link.release(self._kind)

    def kill(self) -> None:
        """End a call inside this client at once (Guarded.drop): the whole connection goes with it."""
        self._link.kill()


class UrRtdeConnector:
    """The driver's Connector for a UR controller: each new receive client starts a new connection (a child); the
    IO and control clients are made in the current one."""

    control_takes_over = True   # RTDEControlInterface uploads its script: another running program ends

    def __init__(self) -> None:
        self._links: dict[str, Link] = {}

    def _current(self, host: str) -> Link:
        link = self._links.get(host)
        if link is None or not link.alive:
            raise RuntimeError(f"no connection to {host}")
        return link

    def receive(self, host: str) -> Client:
        old = self._links.get(host)
        if old is not None:  # (the driver dropped it before it reconnects; a connect it gave up on is ended here)
            old.kill()
        link = Link(host)
        self._links[host] = link
        try:
            return link.make("receive", START_TIMEOUT_S)
        except BaseException:
            link.kill()
            raise

    def io(self, host: str) -> Client:
        return self._current(host).make("io", START_TIMEOUT_S)

    def control(self, host: str) -> Client:
        return self._current(host).make("control", START_TIMEOUT_S)

    def dashboard(self, host: str) -> Any:
        import dashboard_client
        return dashboard_client.DashboardClient(host)


def main(argv: Optional[list[str]] = None) -> None:
    args = argv if argv is not None else sys.argv[1:]
    conn = Connection(int(args[0]))
    serve(conn, args[1])
    # Without destructors: ur_rtde's can abort on a connection that went away (see controller.keep_forever).
    sys.stdout.flush()
    os._exit(0)


if __name__ == "__main__":
    main()
