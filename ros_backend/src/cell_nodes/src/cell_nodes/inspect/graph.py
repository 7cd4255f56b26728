"""The ROS graph as the Inspect page shows it (rostopic list / rosnode info): topics with their type, publishers and
subscribers; nodes with what they publish, subscribe and serve, whether they answer, and the cell file's module that
lists them. Pure: built from the master's getSystemState and getTopicTypes answers."""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Collection, Mapping, Sequence


@dataclass(frozen=True)
class TopicView:
    name: str
    type: str
    publishers: tuple[str, ...]
    subscribers: tuple[str, ...]


@dataclass
class NodeView:
    name: str
    alive: bool = False
    module: str = ""
    publications: list[str] = field(default_factory=list)
    subscriptions: list[str] = field(default_factory=list)
    services: list[str] = field(default_factory=list)


def modules_by_node(modules: Sequence[Any]) -> dict[str, str]:
    """Node name -> the first module of the cell file that lists it (modules: cell_nodes.modules ModuleSpec)."""
    out: dict[str, str] = {}
    for m in modules:
        for n in m.nodes:
            out.setdefault(n, m.name)
    return out


def registered_nodes(system_state: Sequence[Any]) -> list[str]:
    return sorted({n for group in system_state for _name, members in group for n in members})


def build_graph(system_state: Sequence[Any], topic_types: Sequence[Any], alive: Collection[str],
                module_of: Mapping[str, str]) -> tuple[list[TopicView], list[NodeView]]:
    """system_state: [publishers, subscribers, services], each [[name, [node, ...]], ...] (the master's answer);
    topic_types: [[topic, type], ...]. A topic only subscribed still has its type when the master knows it."""
    pubs, subs, srvs = system_state
    types = {t: ty for t, ty in topic_types}
    pub_of = {t: sorted(set(ns)) for t, ns in pubs}
    sub_of = {t: sorted(set(ns)) for t, ns in subs}
    topics = [TopicView(t, types.get(t, ""), tuple(pub_of.get(t, ())), tuple(sub_of.get(t, ())))
              for t in sorted(set(pub_of) | set(sub_of))]
    nodes = {n: NodeView(n, alive=n in alive, module=module_of.get(n, "")) for n in registered_nodes(system_state)}
    for group, attr in ((pubs, "publications"), (subs, "subscriptions"), (srvs, "services")):
        for name, members in group:
            for n in set(members):
                getattr(nodes[n], attr).append(name)
    for v in nodes.values():
        v.publications.sort()
        v.subscriptions.sort()
        v.services.sort()
    return topics, [nodes[n] for n in sorted(nodes)]
