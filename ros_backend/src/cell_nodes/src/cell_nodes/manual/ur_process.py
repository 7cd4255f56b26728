"""ur_rtde in child processes, one per client (receive, IO, control) of a connection: the driver's UR connector.

Why a process: ur_rtde's clients act on threads of their own. When the controller's data pauses for 2.5 s (a
network gap, a loaded host), the control client reconnects on its receive thread, and that reconnect, racing a call
the driver made on another thread, crashed the whole node with SIGSEGV (reproduced by freezing the sim mid-move).
An abandoned control client also keeps reconnecting and takes the controller back from its successor; some calls
hold the GIL while they block, which froze every thread of the node; and the clients' destructors abort the process
after a lost connection. In a child all of that stays in the child: the driver ends it (SIGKILL) when it drops the
client, and a child that dies is a lost connection, which the driver already handles (it reconnects). One child per
client, as in one process the clients were independent: a control client being made (or a call that holds the GIL)
never holds up the polls of the receive client.

A child runs `python -m cell_nodes.manual.ur_process <fd> <host> <kind>` with a socket pair to the parent; requests
are (method, args) on its one client, answered in order. Its stdout and stderr are the node's: ur_rtde's own
messages still reach the node's log.
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
RTDE_PORT = 30004       # the controller's RTDE interface (every ur_rtde client talks to it)
PROBE_TIMEOUT_S = 1.0
CALL_TIMEOUT_S = 12.0   # a call that takes longer ends the child (the gate gives up on it sooner: see Gate)
# The child's start and its client's connection, on a loaded host. Under the driver's own bound for making a client
# (5 s, ManualDriver.connect): a client the driver gave up on has ended its child by then, so none is left behind.
START_TIMEOUT_S = 4.5
CLOSE_TIMEOUT_S = 1.0   # for a client's disconnect when it is dropped cleanly
# The rate each client asks the controller to stream its state at. An e-Series streams at up to 500 Hz, a CB3 at 125;
# the driver reads the state at 125 Hz (ManualDriver's poll_rate), so a faster stream is only work: at 500 Hz each
# client cost the controller's side (the sim) 11 % of a core and its own process 9 %, at 125 Hz 3 % and 5 %.
RECEIVE_HZ = 125.0
CONTROL_HZ = 125.0


def make_client(kind: str, host: str) -> Any:
    """The unmodified ur_rtde client of a kind (in the child)."""
    if kind == "receive":
        import rtde_receive
        return rtde_receive.RTDEReceiveInterface(host, RECEIVE_HZ)
    if kind == "io":
        import rtde_io
        return rtde_io.RTDEIOInterface(host)
    if kind == "control":
        import rtde_control
        # Made without uploading the script: the driver starts it with reuploadScript and waits for it itself, each
        # step bounded (see ManualDriver._control).
        return rtde_control.RTDEControlInterface(host, CONTROL_HZ, int(rtde_control.RTDEControlInterface.FLAG_NO_WAIT))
    raise ValueError(f"unknown client kind {kind!r}")


def serve(conn: Connection, host: str, kind: str, make: Callable[[str, str], Any] = make_client) -> None:
    """The child's loop: one request at a time until the parent goes away (or kills it)."""
    client: Any = None
    while True:
        try:
            name, args = conn.recv()
        except (EOFError, OSError):
            return
        try:
            if name == "__make__":
                client = make(kind, host)
                result: Any = None
            elif name == "readState":
                result = tuple(getattr(client, g)() for g in STATE_GETTERS)
            else:
                result = getattr(client, name)(*args)
            reply: tuple[str, Any] = ("ok", result)
        except Exception as e:  # ur_rtde raises RuntimeError with its own text: the parent raises it again
            reply = ("error", f"{e}" or type(e).__name__)
        try:
            conn.send(reply)
        except (EOFError, OSError):
            return


class Client:
    """One ur_rtde client in its own child, with its methods' names (the driver's Receive/IO/ControlInterface)."""

    def __init__(self, host: str, kind: str) -> None:
        self._host, self._kind = host, kind
        parent, child = socket.socketpair()
        for end in (parent, child):  # (a default socket timeout, which rospy sets, would make them non-blocking)
            end.setblocking(True)
        try:
            self._proc = subprocess.Popen([sys.executable, "-m", "cell_nodes.manual.ur_process", str(child.fileno()),
                                           host, kind], pass_fds=(child.fileno(),), stdin=subprocess.DEVNULL)
        finally:
            child.close()
        self._conn = Connection(parent.detach())
        self._lock = threading.Lock()
        self._ended = False
        try:
            self._call("__make__", (), START_TIMEOUT_S)
        except BaseException:
            self.kill()
            raise

    def _call(self, name: str, args: tuple = (), timeout: float = CALL_TIMEOUT_S) -> Any:
        with self._lock:
            if self._ended:
                raise ClientGone(f"{name}: the {self._kind} client of {self._host} was closed")
            try:
                self._conn.send((name, args))
                if not self._conn.poll(timeout):
                    self.kill()
                    raise CallTimeout(f"{name}: no answer within {timeout:g} s")
                status, value = self._conn.recv()
            except (EOFError, OSError):
                self.kill()
                raise RuntimeError(f"the ur_rtde {self._kind} process for {self._host} ended (exit code "
                                   f"{self._proc.poll()})") from None
        if status == "error":
            raise RuntimeError(value)
        return value

    def __getattr__(self, name: str) -> Callable[..., Any]:
        if name.startswith("_") or name not in METHODS[self._kind]:
            raise AttributeError(name)
        return lambda *args: self._call(name, args)

    def disconnect(self) -> None:
        """Disconnect (bounded in time), then end the child."""
        if not self._ended:
            try:
                self._call("disconnect", (), CLOSE_TIMEOUT_S)
            except Exception:
                pass  # (a lost connection's disconnect may fail or hang: the child ends below either way)
        self.kill()

    def kill(self) -> None:
        """End the child now (a call waiting on it returns with an error); safe from any thread, more than once.
        Guarded.drop uses it to end a call inside the client instead of waiting for it."""
        self._ended = True
        if self._proc.poll() is None:
            self._proc.kill()
        # Reaped by a thread: wait() returns at once after SIGKILL, unless the host is very busy.
        threading.Thread(target=self._proc.wait, name="ur-reap", daemon=True).start()


class UrRtdeConnector:
    """The driver's Connector for a UR controller: each client in a child of its own."""

    control_takes_over = True   # RTDEControlInterface uploads its script: another running program ends

    def receive(self, host: str) -> Client:
        # A connection starts here: while the controller does not answer, fail without starting a child (the driver
        # retries every second; a Python process each time would cost a good part of a core).
        try:
            socket.create_connection((host, RTDE_PORT), timeout=PROBE_TIMEOUT_S).close()
        except OSError as e:
            raise RuntimeError(f"RTDE at {host}:{RTDE_PORT}: {e.strerror or e}") from None
        return Client(host, "receive")

    def io(self, host: str) -> Client:
        return Client(host, "io")

    def control(self, host: str) -> Client:
        return Client(host, "control")

    def dashboard(self, host: str) -> Any:
        import dashboard_client
        return dashboard_client.DashboardClient(host)


def main(argv: Optional[list[str]] = None) -> None:
    args = argv if argv is not None else sys.argv[1:]
    conn = Connection(int(args[0]))
    serve(conn, args[1], args[2])
    # Without destructors: ur_rtde's can abort on a connection that went away (see controller.keep_forever).
    sys.stdout.flush()
    os._exit(0)


if __name__ == "__main__":
    main()
