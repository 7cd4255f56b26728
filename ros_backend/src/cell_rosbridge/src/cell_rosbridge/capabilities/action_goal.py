"""send_action_goal / cancel_action_goal (client -> server) and their action_feedback / action_result (server ->
client), as rosbridge_suite's ROS 2 server has them: the goal runs off the event loop and always ends in one
action_result: with the result's values and GoalStatus when the server gave one (result true), or with the
reason and status 0 (unknown) when it could not (no server, rejected, bad goal, client gone; result false).
"""
from __future__ import annotations

import itertools
import threading
from typing import Any, Dict

from .. import conversion
from ..op_base import COMPRESSIONS, ProtocolError, check, number, require
from ..plumbing import ActionGoalError, resolve_topic, send_action_goal as ros_send_goal

_anon = itertools.count(1)
STATUS_UNKNOWN = 0


def send_action_goal(client: Any, msg: Dict[str, Any]) -> None:
    action = resolve_topic(require(msg, "action", str))
    action_type = require(msg, "action_type", str)
    args = msg.get("args")
    if args is not None and not isinstance(args, (dict, list)):
        raise ProtocolError(f"field 'args' must be an object or a list, got {type(args).__name__}")
    if isinstance(args, list):  # an empty list is the spec's "no args"
        if args:
            raise ProtocolError("field 'args' must be an object with the goal's fields")
        args = {}
    feedback = check(msg, "feedback", bool, False)
    fragment_size = int(number(msg, "fragment_size", 0))
    compression = check(msg, "compression", str, "none")
    if compression not in COMPRESSIONS:
        raise ProtocolError(f"unsupported compression '{compression}'")
    gid = msg.get("id")
    key = gid if isinstance(gid, (str, int)) and not isinstance(gid, bool) else f"goal:{next(_anon)}"
    use_cbor = compression in ("cbor", "cbor-raw")
    goals: Dict[Any, Any] = client.__dict__.setdefault("action_goals", {})
    with client.lock:
        if key in goals:
            raise ProtocolError(f"a goal with id {key!r} is still running")
        if client.pending_calls >= client.context.config.max_pending_calls:
            raise ProtocolError(f"too many concurrent calls and goals (max {client.context.config.max_pending_calls})")
        client.pending_calls += 1
        goals[key] = None

    def reply(out: Dict[str, Any]) -> None:
        out["action"] = action
        if gid is not None:
            out["id"] = gid
        client.send_encoded(out, compression, fragment_size)

    def on_feedback(fb: Any) -> None:
        if feedback:
            reply({"op": "action_feedback", "values": conversion.msg_to_dict(fb, cbor=use_cbor)})

    def worker() -> None:
        try:
            status, result = ros_send_goal(action, action_type, args or {}, on_feedback,
                                           lambda handle: goals.__setitem__(key, handle))
            reply({"op": "action_result", "values": conversion.msg_to_dict(result, cbor=use_cbor),
                   "status": status, "result": True})
        except (ActionGoalError, conversion.ConversionError, conversion.UnknownTypeError) as exc:
            reply({"op": "action_result", "values": str(exc), "status": STATUS_UNKNOWN, "result": False})
        except Exception as exc:  # anything else still ends the goal for the client
            reply({"op": "action_result", "values": f"{type(exc).__name__}: {exc}", "status": STATUS_UNKNOWN,
                   "result": False})
        finally:
            with client.lock:
                goals.pop(key, None)
                client.pending_calls -= 1

    threading.Thread(target=worker, name=f"goal {action}", daemon=True).start()


def cancel_action_goal(client: Any, msg: Dict[str, Any]) -> None:
    resolve_topic(require(msg, "action", str))
    gid = require(msg, "id", (str, int))
    goals: Dict[Any, Any] = client.__dict__.get("action_goals", {})
    with client.lock:
        if gid not in goals:
            raise ProtocolError(f"no goal with id {gid!r} is running")
        handle = goals[gid]
    if handle is not None:
        handle.cancel()  # the goal's own action_result follows, with status canceled


def finish(client: Any) -> None:
    """A client that leaves cancels its goals: nobody would see them end (and a moving arm must not go on)."""
    for handle in list(client.__dict__.get("action_goals", {}).values()):
        if handle is not None:
            try:
                handle.cancel()
            except Exception:
                pass
