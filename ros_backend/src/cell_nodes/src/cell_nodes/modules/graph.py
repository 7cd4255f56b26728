"""Which nodes are alive, from the ROS master's XML-RPC API, and stopping nodes by name.

The master keeps listing a node that died without unregistering (kill -9, a crash) until someone cleans it up, so
a node counts as alive only when it is registered and answers a ping (`getPid` on its own XML-RPC API), like
`rosnode ping`. A node whose API refuses the connection is dead: its registrations are removed from the master
(like `rosnode cleanup`), so the next check, the BFF and `rosnode list` agree. A node that does not answer within
the ping timeout counts as not alive for that check but keeps its registrations (it may only be busy).

Every call has a timeout and the pings run in parallel, so one hung node costs one ping timeout per check, not
one per node. No rospy: plain xmlrpc.client, testable against any XML-RPC server.
"""
from __future__ import annotations

import errno
import http.client
import socket
import xmlrpc.client
from concurrent.futures import ThreadPoolExecutor
from typing import Any, Collection, Optional, Protocol


# Parameters every rospy node that logs subscribes to (rospy.impl.rosout).
ROSPY_PARAM_SUBSCRIPTIONS = ("/rosout_disable_topics_generation",)


class GraphError(RuntimeError):
    """The master cannot be reached."""


class Graph(Protocol):
    def alive(self, nodes: Collection[str]) -> set[str]:
        """The names among `nodes` that are alive right now (raises GraphError without a master)."""

    def kill(self, nodes: Collection[str]) -> list[str]:
        """Ask these nodes to shut down (the `rosnode kill` way); returns the names that were asked."""


class _TimeoutTransport(xmlrpc.client.Transport):
    def __init__(self, timeout: float) -> None:
        super().__init__()
        self._timeout = timeout

    def make_connection(self, host: Any) -> http.client.HTTPConnection:
        conn = super().make_connection(host)
        conn.timeout = self._timeout
        return conn


def _proxy(uri: str, timeout: float) -> xmlrpc.client.ServerProxy:
    return xmlrpc.client.ServerProxy(uri, transport=_TimeoutTransport(timeout), allow_none=True)


def _refused(e: BaseException) -> bool:
    return isinstance(e, ConnectionRefusedError) or getattr(e, "errno", None) == errno.ECONNREFUSED


class MasterGraph:
    def __init__(self, master_uri: str, caller_id: str, ping_timeout: float = 1.0, master_timeout: float = 2.0,
                 workers: int = 8, clean_up: bool = True) -> None:
        self.master_uri = master_uri
        self.clean_up = clean_up  # False: only look (the Inspect page's graph changes nothing)
        self.caller_id = caller_id
        self.ping_timeout = ping_timeout
        self.master_timeout = master_timeout
        self._pool = ThreadPoolExecutor(max_workers=workers, thread_name_prefix="modules-ping")
        self.cleaned: list[str] = []  # nodes whose stale registrations this graph removed (for the log)

    def close(self) -> None:
        self._pool.shutdown(wait=False, cancel_futures=True)

    # ------------------------------------------------------------------ master calls
    def _master(self, method: str, *args: Any, caller: Optional[str] = None) -> Any:
        try:
            code, msg, val = getattr(_proxy(self.master_uri, self.master_timeout), method)(caller or self.caller_id,
                                                                                            *args)
        except (OSError, xmlrpc.client.Error, http.client.HTTPException) as e:
            raise GraphError(f"the ROS master at {self.master_uri} does not answer: {e}") from e
        if code != 1:
            raise LookupError(msg)
        return val

    def system_state(self) -> list[Any]:
        return self._master("getSystemState")

    def topic_types(self) -> list[Any]:
        return self._master("getTopicTypes")

    def lookup(self, node: str) -> Optional[str]:
        try:
            return self._master("lookupNode", node)
        except LookupError:
            return None

    # ------------------------------------------------------------------ liveness
    def _ping(self, node: str) -> tuple[str, Optional[str], str]:
        """(node, its API URI, verdict): alive, dead (refused: gone for good), silent (no answer in time)."""
        try:
            uri = self.lookup(node)
        except GraphError:
            return node, None, "silent"
        if not uri:
            return node, None, "dead"
        try:
            code, _msg, _pid = _proxy(uri, self.ping_timeout).getPid(self.caller_id)
            return node, uri, "alive" if code == 1 else "silent"
        except (socket.timeout, TimeoutError):
            return node, uri, "silent"
        except OSError as e:
            return node, uri, "dead" if _refused(e) else "silent"
        except (xmlrpc.client.Error, http.client.HTTPException):
            return node, uri, "silent"

    def alive(self, nodes: Collection[str]) -> set[str]:
        state = self.system_state()
        registered = {n for group in state for _name, members in group for n in members}
        wanted = [n for n in dict.fromkeys(nodes) if n in registered]
        results = list(self._pool.map(self._ping, wanted))
        for node, uri, verdict in results:
            if verdict == "dead" and uri and self.clean_up:
                self._unregister(node, uri, state)
        return {node for node, _uri, verdict in results if verdict == "alive"}

    def _unregister(self, node: str, uri: str, state: list[Any]) -> None:
        """Remove a dead node's registrations (the master only removes the ones made with this very URI)."""
        pubs, subs, srvs = state
        try:
            if self.lookup(node) != uri:
                return  # registered again meanwhile (a new process under the same name)
            for topic, members in pubs:
                if node in members:
                    self._master("unregisterPublisher", topic, uri, caller=node)
            for topic, members in subs:
                if node in members:
                    self._master("unregisterSubscriber", topic, uri, caller=node)
            for service, members in srvs:
                if node in members:
                    try:
                        service_uri = self._master("lookupService", service)
                    except LookupError:
                        continue
                    self._master("unregisterService", service, service_uri, caller=node)
            # rospy's log handler subscribes this parameter: the master forgets the node once it is gone too
            for key in ROSPY_PARAM_SUBSCRIPTIONS:
                self._master("unsubscribeParam", uri, key, caller=node)
            self.cleaned.append(node)
        except (GraphError, LookupError):
            pass  # the next check tries again

    # ------------------------------------------------------------------ stopping
    def kill(self, nodes: Collection[str]) -> list[str]:
        def one(node: str) -> Optional[str]:
            try:
                uri = self.lookup(node)
            except GraphError:
                return None
            if not uri:
                return None
            try:
                _proxy(uri, self.ping_timeout).shutdown(self.caller_id, "stopped by the modules node")
            except (OSError, xmlrpc.client.Error, http.client.HTTPException):
                pass  # it may go down while answering: like rosnode kill, count it as asked
            return node

        return [n for n in self._pool.map(one, list(dict.fromkeys(nodes))) if n]
