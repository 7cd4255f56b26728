"""call_service (client -> server): call a ROS service off the event loop; always answer.

A missing service, bad args or a timeout produce service_response with result false and the reason
in values (what rosbridge does), so a client never waits forever.
"""
from __future__ import annotations

import threading
from typing import Any, Dict

from .. import conversion
from ..op_base import COMPRESSIONS, ProtocolError, check, number, require
from ..plumbing import ServiceCallError, call_service as ros_call, resolve_topic


def call_service(client: Any, msg: Dict[str, Any]) -> None:
    service = resolve_topic(require(msg, "service", str))
    args = msg.get("args")
    if args is not None and not isinstance(args, (dict, list)):
        raise ProtocolError(f"field 'args' must be an object or a list, got {type(args).__name__}")
    fragment_size = int(number(msg, "fragment_size", 0))
    compression = check(msg, "compression", str, "none")
    if compression not in COMPRESSIONS:
        raise ProtocolError(f"unsupported compression '{compression}'")
    timeout = number(msg, "timeout", None, minimum=0.001, maximum=86400)
    msg_id = msg.get("id")
    with client.lock:
        if client.pending_calls >= client.context.config.max_pending_calls:
            raise ProtocolError(f"too many concurrent service calls (max {client.context.config.max_pending_calls})")
        client.pending_calls += 1

    done = threading.Lock()
    answered = [False]
    use_cbor = compression in ("cbor", "cbor-raw")

    def answer(values: Any, result: bool) -> None:
        with done:
            if answered[0]:
                return
            answered[0] = True
        out: Dict[str, Any] = {"op": "service_response", "service": service, "values": values, "result": result}
        if msg_id is not None:
            out["id"] = msg_id
        client.send_encoded(out, compression, fragment_size)

    def worker() -> None:
        try:
            _, response = ros_call(service, args)
            answer(conversion.msg_to_dict(response, cbor=use_cbor), True)
        except (ServiceCallError, conversion.ConversionError, conversion.UnknownTypeError) as exc:
            answer(str(exc), False)
        except Exception as exc:  # anything else still gets an answer
            answer(f"{type(exc).__name__}: {exc}", False)
        finally:
            with client.lock:
                client.pending_calls -= 1

    if timeout is not None:
        timer = threading.Timer(float(timeout), answer,
                                args=(f"service {service} timed out after {timeout} s", False))
        timer.daemon = True
        timer.start()
    threading.Thread(target=worker, name=f"call {service}", daemon=True).start()
