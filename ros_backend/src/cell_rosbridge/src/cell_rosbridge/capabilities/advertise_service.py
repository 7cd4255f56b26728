"""advertise_service / unadvertise_service / service_response: a client serves a ROS service.

ROS callers hit a ROS service (plumbing.serve) whose handler forwards the request to the client as a call_service op
and blocks (in rospy's connection thread) until the matching service_response, a timeout, or the
client going away, which fails every pending call instead of leaving callers hanging.
"""
from __future__ import annotations

import itertools
import threading
from typing import Any, Dict, Tuple

from .. import conversion
from ..op_base import ProtocolError, check, require
from ..plumbing import ServiceFailure, other_providers, resolve_topic, serve

_request_ids = itertools.count(1)


class AdvertisedService:
    def __init__(self, client: Any, name: str, type_name: str) -> None:
        self.client = client
        self.name = name
        self.type_name = conversion.normalize_type(type_name)
        self.srv_cls = conversion.get_service_class(self.type_name)
        self.pending: Dict[str, Tuple[threading.Event, Dict[str, Any]]] = {}
        self.lock = threading.Lock()
        self.closed = False
        self._withdraw = serve(name, self.srv_cls, self._handle)

    def _handle(self, request: Any) -> Any:
        rid = f"service_request:{self.name}:{next(_request_ids)}"
        event, slot = threading.Event(), {}
        with self.lock:
            if self.closed:
                raise ServiceFailure(f"service {self.name} is no longer served")
            self.pending[rid] = (event, slot)
        try:
            self.client.send({"op": "call_service", "id": rid, "service": self.name,
                              "args": conversion.msg_to_dict(request)})
            if not event.wait(self.client.context.config.service_request_timeout):
                raise ServiceFailure(f"client did not answer {self.name} in time")
        finally:
            with self.lock:
                self.pending.pop(rid, None)
        if slot.get("error"):
            raise ServiceFailure(slot["error"])
        if not slot.get("result"):
            raise ServiceFailure(f"client reported failure: {slot.get('values')!r}")
        return conversion.dict_to_msg(conversion.response_class(self.srv_cls), slot.get("values") or {})

    def respond(self, rid: str, values: Any, result: bool) -> bool:
        with self.lock:
            entry = self.pending.get(rid)
        if entry is None:
            return False
        event, slot = entry
        slot.update(values=values, result=result)
        event.set()
        return True

    def shutdown(self, reason: str) -> None:
        with self.lock:
            self.closed = True
            pending = list(self.pending.values())
        for event, slot in pending:
            slot["error"] = reason
            event.set()
        self._withdraw(reason)


def advertise_service(client: Any, msg: Dict[str, Any]) -> None:
    name = resolve_topic(require(msg, "service", str))
    type_name = require(msg, "type", str)
    ctx = client.context
    others = other_providers(name)
    if others:  # a browser must not hijack a real ROS service (e.g. /rosapi/*)
        raise ProtocolError(f"service {name} is already provided by {', '.join(others)}")
    with ctx.lock:
        existing = ctx.services.get(name)
        if existing is not None and existing.client is not client:
            raise ProtocolError(f"service {name} is already advertised by another client")
        if existing is not None:  # re-advertise replaces (type may change)
            existing.shutdown("re-advertised")
        svc = AdvertisedService(client, name, type_name)
        ctx.services[name] = svc
        client.services[name] = svc


def unadvertise_service(client: Any, msg: Dict[str, Any]) -> None:
    name = resolve_topic(require(msg, "service", str))
    _remove(client, name, "unadvertised")


def _remove(client: Any, name: str, reason: str) -> None:
    ctx = client.context
    with ctx.lock:
        svc = client.services.pop(name, None)
        if svc is None:
            raise ProtocolError(f"service {name} is not advertised by this client")
        if ctx.services.get(name) is svc:
            del ctx.services[name]
    svc.shutdown(reason)


def service_response(client: Any, msg: Dict[str, Any]) -> None:
    name = resolve_topic(require(msg, "service", str))
    rid = msg.get("id")
    if rid is None:
        raise ProtocolError("missing field 'id'")
    result = check(msg, "result", bool, True)
    svc = client.services.get(name)
    if svc is None:
        raise ProtocolError(f"service {name} is not advertised by this client")
    if not svc.respond(rid, msg.get("values"), result):
        raise ProtocolError(f"no pending request {rid!r} for {name}")


def finish(client: Any) -> None:
    for name in list(client.services):
        try:
            _remove(client, name, "client disconnected")
        except ProtocolError:
            pass
