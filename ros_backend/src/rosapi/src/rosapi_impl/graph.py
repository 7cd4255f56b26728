"""Master queries and message-definition introspection behind the rosapi services."""
from __future__ import annotations

import fnmatch
import json
import threading
from typing import Any, Dict, List, Optional, Tuple

import genpy
import rosgraph
import roslib.message
import rosservice

from rosapi.msg import TypeDef

# One master proxy for every service thread, one call at a time. rospy serves each call on a new thread, and an
# XML-RPC connection (http.client) is not safe to share. A proxy per thread (the earlier way) left each thread's
# socket to the garbage collector; tracemalloc showed its buffers retained, ~250 B per call, a steady leak in the
# soak. Master queries take about a millisecond.
class _SharedMaster:
    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._master: Optional[rosgraph.Master] = None

    def __getattr__(self, name: str) -> Any:
        def call(*args: Any) -> Any:
            with self._lock:
                if self._master is None:
                    self._master = rosgraph.Master("/rosapi")
                return getattr(self._master, name)(*args)
        return call


_master = _SharedMaster()


def master() -> Any:
    return _master


def system_state() -> Tuple[List[Any], List[Any], List[Any]]:
    return master().getSystemState()


def topics_and_types() -> Tuple[List[str], List[str]]:
    pairs = sorted(master().getTopicTypes())
    return [t for t, _ in pairs], [ty for _, ty in pairs]


def services() -> List[str]:
    return sorted(s for s, _ in system_state()[2])


def service_type(name: str) -> str:
    # rosservice.get_service_type makes a master proxy per call and leaves its socket to the garbage collector.
    try:
        return rosservice.get_service_headers(name, master().lookupService(name)).get("type", "")
    except Exception:  # unknown service or dead provider: no type
        return ""


def service_node(name: str) -> str:
    for svc, nodes in system_state()[2]:
        if svc == name and nodes:
            return nodes[0]
    return ""


def service_host(name: str) -> str:
    try:
        uri = master().lookupService(name)
    except Exception:
        return ""
    return uri.split("//", 1)[-1].split(":", 1)[0]


def nodes() -> List[str]:
    seen = set()
    for group in system_state():
        for _, names in group:
            seen.update(names)
    return sorted(seen)


def node_details(node: str) -> Tuple[List[str], List[str], List[str]]:
    pubs, subs, srvs = system_state()
    pick = lambda group: sorted(name for name, nodes in group if node in nodes)  # noqa: E731
    return pick(subs), pick(pubs), pick(srvs)


def publishers(topic: str) -> List[str]:
    return next((sorted(n) for t, n in system_state()[0] if t == topic), [])


def subscribers(topic: str) -> List[str]:
    return next((sorted(n) for t, n in system_state()[1] if t == topic), [])


def action_servers() -> List[str]:
    """Namespaces publishing the five actionlib topics (status/feedback/result out, goal/cancel in)."""
    topics = {t for t, _ in master().getTopicTypes()}
    out = []
    for t in topics:
        if t.endswith("/status"):
            ns = t[: -len("/status")]
            if {f"{ns}/goal", f"{ns}/cancel", f"{ns}/result", f"{ns}/feedback"} <= topics:
                out.append(ns)
    return sorted(out)


def typedefs(cls: type) -> List[TypeDef]:
    """TypeDef list for a message class and every nested type (roslib's decodeTypeDefs reads this)."""
    out: List[TypeDef] = []
    seen: Dict[str, bool] = {}
    _walk(cls, out, seen)
    return out


_BUILTIN_TIME = {"time": ("secs", "nsecs"), "duration": ("secs", "nsecs")}


def _walk(cls: type, out: List[TypeDef], seen: Dict[str, bool]) -> None:
    if cls._type in seen:
        return
    seen[cls._type] = True
    td = TypeDef(type=cls._type)
    out.append(td)  # the requested type comes first, nested ones after (roslib relies on it)
    nested: List[type] = []
    for name, slot_type in zip(cls.__slots__, cls._slot_types):
        base, is_array, length = _split(slot_type)
        td.fieldnames.append(name)
        td.fieldtypes.append(base)
        td.fieldarraylen.append(-1 if not is_array else (length if length is not None else 0))
        if base in _BUILTIN_TIME:
            td.examples.append("{}")
            out_time = TypeDef(type=base, fieldnames=["secs", "nsecs"], fieldtypes=["int32", "int32"],
                               fieldarraylen=[-1, -1], examples=["0", "0"])
            if base not in seen:
                seen[base] = True
                out.append(out_time)
        elif "/" in base or base == "Header":
            td.examples.append("{}" if not is_array else "[]")
            sub = roslib.message.get_message_class(base if base != "Header" else "std_msgs/Header")
            if sub is not None:
                nested.append(sub)
        else:
            td.examples.append("[]" if is_array else _primitive_example(base))
    consts = [(n, getattr(cls, n)) for n in dir(cls) if n.isupper() and not n.startswith("_")]
    for n, v in consts:
        td.constnames.append(n)
        td.constvalues.append(str(v))
    for sub in nested:
        _walk(sub, out, seen)


def _primitive_example(base: str) -> str:
    if base in ("float32", "float64"):
        return "0.0"
    if base == "bool":
        return "False"
    if base == "string":
        return ""
    return "0"


def _split(slot_type: str) -> Tuple[str, bool, Optional[int]]:
    if not slot_type.endswith("]"):
        return slot_type, False, None
    base, _, rest = slot_type.partition("[")
    return base, True, int(rest[:-1]) if rest[:-1] else None


def full_text(type_name: str) -> str:
    cls = roslib.message.get_message_class(type_name)
    return cls._full_text if cls is not None else ""


def param_value_json(name: str, default: str) -> str:
    """rosapi's convention: parameter values travel as JSON text."""
    import rospy
    if rospy.has_param(name):
        return json.dumps(rospy.get_param(name))
    return default


def set_param_json(name: str, value: str) -> None:
    import rospy
    try:
        parsed = json.loads(value)
    except ValueError:
        parsed = value  # a bare string that is not JSON is stored as that string
    rospy.set_param(name, parsed)


def param_names() -> List[str]:
    import rospy
    return sorted(rospy.get_param_names())


def topics_for_type(type_name: str) -> List[str]:
    return [t for t, ty in sorted(master().getTopicTypes()) if ty == type_name]


def services_for_type(type_name: str) -> List[str]:
    return [s for s in services() if service_type(s) == type_name]


_ = fnmatch  # reserved for glob filters (rosapi's topics_glob params), not used yet
