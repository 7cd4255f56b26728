"""One module per rosbridge op; HANDLERS maps op -> handler, FINALIZERS release a client's resources."""
from __future__ import annotations

from typing import Any, Callable, Dict, List

from . import advertise, advertise_service, call_service, fragment, publish, status, subscribe

HANDLERS: Dict[str, Callable[[Any, Dict[str, Any]], None]] = {
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
}

FINALIZERS: List[Callable[[Any], None]] = [subscribe.finish, advertise.finish, advertise_service.finish]
