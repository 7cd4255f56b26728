"""One module per rosbridge op; HANDLERS maps op -> handler, FINALIZERS release a client's resources.

The modules import only op_base / conversion / plumbing (never protocol.py or each other);
`register_all` wires them into a BridgeContext, called by whoever builds the server (node.build_context).
"""
from __future__ import annotations

from typing import Dict, List, Protocol

from ..op_base import Finalizer, Handler
from . import action_goal, advertise, advertise_service, call_service, fragment, publish, status, subscribe

HANDLERS: Dict[str, Handler] = {
    "advertise": advertise.advertise,
    "unadvertise": advertise.unadvertise,
    "publish": publish.publish,
    "subscribe": subscribe.subscribe,
    "unsubscribe": subscribe.unsubscribe,
    "call_service": call_service.call_service,
    "advertise_service": advertise_service.advertise_service,
    "unadvertise_service": advertise_service.unadvertise_service,
    "service_response": advertise_service.service_response,
    "set_level": status.set_level,
    "status": status.ignore,  # server->client op; a client echoing one is harmless
    "auth": status.ignore,  # authentication is done by the BFF in front of us (spec: may be ignored)
    "fragment": fragment.fragment,
    "send_action_goal": action_goal.send_action_goal,
    "cancel_action_goal": action_goal.cancel_action_goal,
}

FINALIZERS: List[Finalizer] = [subscribe.finish, advertise.finish, advertise_service.finish, action_goal.finish]


class Registry(Protocol):
    """What register_all needs of a BridgeContext (structural, so this package never imports protocol)."""

    def register(self, op: str, handler: Handler) -> None: ...

    def add_finalizer(self, finalizer: Finalizer) -> None: ...


def register_all(context: Registry) -> None:
    """Register every op and cleanup step with a dispatcher context."""
    for op, handler in HANDLERS.items():
        context.register(op, handler)
    for finalizer in FINALIZERS:
        context.add_finalizer(finalizer)
