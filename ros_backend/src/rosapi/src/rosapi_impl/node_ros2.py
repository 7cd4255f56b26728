"""rosapi on ROS 2: /rosapi/* under the names and rosapi_msgs types of rosbridge_suite's ROS 2 rosapi, answered
from rclpy's graph queries. Type names are given as ROS 2 spells them (`std_msgs/msg/String`); typedefs name
nested types the same way, so roslib's decodeTypeDefs links them up.

Parameters live in the nodes on ROS 2 (no parameter server): a name is `<node>:<parameter>` (`/rosbridge_websocket:port`),
read and written through the node's rcl_interfaces parameter services; values travel as JSON text, as on ROS 1.
"""
from __future__ import annotations

import json
import sys
import threading
from typing import Any, Callable, Dict, List, Optional, Tuple

import rclpy
from rclpy.callback_groups import ReentrantCallbackGroup
from rclpy.executors import MultiThreadedExecutor
from rclpy.node import Node
from rclpy.parameter import Parameter, parameter_value_to_python

from cell_nodes import priority
from cell_rosbridge import types_ros2
from rosapi_msgs import srv
from rosapi_msgs.msg import TypeDef

NS = "/rosapi/"
_PRIMITIVE_EXAMPLES = {"float32": "0.0", "float64": "0.0", "bool": "False", "string": ""}


class Graph:
    """The graph as rosapi answers it, from one rclpy node."""

    def __init__(self, node: Node) -> None:
        self.node = node

    def topics_and_types(self) -> Tuple[List[str], List[str]]:
        pairs = sorted((name, types[0]) for name, types in self.node.get_topic_names_and_types() if types)
        return [t for t, _ in pairs], [ty for _, ty in pairs]

    def services_and_types(self) -> Dict[str, str]:
        return {name: types[0] for name, types in self.node.get_service_names_and_types() if types}

    def nodes(self) -> List[str]:
        return sorted(f"{ns.rstrip('/')}/{name}" for name, ns in self.node.get_node_names_and_namespaces())

    def _split_node(self, full: str) -> Tuple[str, str]:
        ns, _, name = full.rpartition("/")
        return name, ns or "/"

    def node_details(self, full: str) -> Tuple[List[str], List[str], List[str]]:
        name, ns = self._split_node(full)
        try:
            subs = self.node.get_subscriber_names_and_types_by_node(name, ns)
            pubs = self.node.get_publisher_names_and_types_by_node(name, ns)
            srvs = self.node.get_service_names_and_types_by_node(name, ns)
        except Exception:  # no such node (any more)
            return [], [], []
        return sorted(t for t, _ in subs), sorted(t for t, _ in pubs), sorted(s for s, _ in srvs)

    def endpoints(self, topic: str, publishers: bool) -> List[str]:
        infos = (self.node.get_publishers_info_by_topic if publishers else self.node.get_subscriptions_info_by_topic)(
            topic)
        return sorted({f"{i.node_namespace.rstrip('/')}/{i.node_name}" for i in infos})

    def service_providers(self, service: str) -> List[str]:
        return sorted(n for n in self.nodes() if service in self.node_details(n)[2])

    def action_servers(self) -> List[str]:
        """Names with an action server's services (send_goal, get_result, cancel_goal)."""
        services = self.services_and_types()
        return sorted(s[: -len("/_action/send_goal")] for s in services if s.endswith("/_action/send_goal"))


def ros2_name(cls: type) -> str:
    package, kind = cls.__module__.split(".")[:2]
    return f"{package}/{kind}/{cls.__name__}"


def typedefs(cls: type) -> List[TypeDef]:
    """TypeDef list for a message class and every nested type, the requested one first (roslib relies on it)."""
    out: List[TypeDef] = []
    seen: set = set()

    def walk(c: type) -> None:
        name = ros2_name(c)
        if name in seen:
            return
        seen.add(name)
        td = TypeDef(type=name)
        out.append(td)
        nested: List[type] = []
        for field, ros2_type in c.get_fields_and_field_types().items():
            base, is_array, length = types_ros2.split_type(ros2_type)
            sub = types_ros2.load_message(base) if "/" in base else None
            td.fieldnames.append(field)
            td.fieldtypes.append(ros2_name(sub) if sub is not None else base)
            td.fieldarraylen.append(-1 if not is_array else (length if length is not None else 0))
            if sub is not None:
                td.examples.append("[]" if is_array else "{}")
                nested.append(sub)
            else:
                td.examples.append("[]" if is_array else _PRIMITIVE_EXAMPLES.get(base, "0"))
        for const in sorted(n for n in dir(c) if n.isupper() and not n.startswith("_")):
            value = getattr(c, const)
            if isinstance(value, (int, float, str, bool)):
                td.constnames.append(const)
                td.constvalues.append(str(value))
        for sub in nested:
            walk(sub)

    walk(cls)
    return out


def _class(type_name: str, loader: Callable[[str], Optional[type]]) -> Optional[type]:
    try:
        return loader(type_name)
    except ValueError:
        return None


class Params:
    """`<node>:<parameter>` through the node's parameter services."""

    def __init__(self, node: Node, group: ReentrantCallbackGroup) -> None:
        self.node, self.group = node, group

    def _call(self, node_name: str, service: str, srv_cls: type, request: Any) -> Any:
        client = self.node.create_client(srv_cls, f"{node_name}/{service}", callback_group=self.group)
        try:
            if not client.wait_for_service(timeout_sec=1.0):
                return None
            done = threading.Event()
            future = client.call_async(request)
            future.add_done_callback(lambda _f: done.set())
            return future.result() if done.wait(5.0) and future.exception() is None else None
        finally:
            self.node.destroy_client(client)

    @staticmethod
    def split(name: str) -> Tuple[str, str]:
        node_name, sep, param = name.partition(":")
        if not sep or not node_name or not param:
            return "", ""
        return ("/" + node_name.lstrip("/")), param

    def get(self, name: str) -> Optional[Any]:
        from rcl_interfaces.srv import GetParameters
        node_name, param = self.split(name)
        if not node_name:
            return None
        answer = self._call(node_name, "get_parameters", GetParameters, GetParameters.Request(names=[param]))
        if answer is None or not answer.values or answer.values[0].type == 0:  # PARAMETER_NOT_SET
            return None
        return parameter_value_to_python(answer.values[0])

    def set(self, name: str, value: str) -> None:
        from rcl_interfaces.srv import SetParameters
        node_name, param = self.split(name)
        if not node_name:
            return
        try:
            parsed = json.loads(value)
        except ValueError:
            parsed = value  # a bare string that is not JSON is that string
        request = SetParameters.Request(parameters=[Parameter(param, value=parsed).to_parameter_msg()])
        self._call(node_name, "set_parameters", SetParameters, request)

    def names(self, graph: Graph) -> List[str]:
        from rcl_interfaces.srv import ListParameters
        out: List[str] = []
        for full in graph.nodes():
            if f"{full}/list_parameters" not in graph.services_and_types():
                continue
            answer = self._call(full, "list_parameters", ListParameters, ListParameters.Request())
            if answer is not None:
                out += [f"{full}:{p}" for p in answer.result.names]
        return sorted(out)


def main(argv: Any = None) -> None:
    rclpy.init(args=argv)
    node = Node("rosapi")
    node.get_logger().info(priority.claim(priority.DEFERRABLE, "rosapi (graph queries)"))
    group = ReentrantCallbackGroup()
    graph = Graph(node)
    params = Params(node, group)

    def serve(name: str, srv_cls: type, fn: Callable[[Any], Any]) -> None:
        node.create_service(srv_cls, NS + name, lambda request, _response: fn(request), callback_group=group)

    def details(type_name: str, part: str) -> List[TypeDef]:
        if part == "msg":
            cls = _class(type_name, types_ros2.load_message)
        else:
            service = _class(type_name, types_ros2.load_service)
            cls = getattr(service, part) if service is not None else None
        return typedefs(cls) if cls is not None else []

    def full_text(type_name: str) -> str:
        cls = _class(type_name, types_ros2.load_message)
        if cls is None:
            return ""
        return "\n".join(f"{t} {n}" for n, t in cls.get_fields_and_field_types().items())

    serve("topics", srv.Topics, lambda r: srv.Topics.Response(**dict(zip(("topics", "types"),
                                                                         graph.topics_and_types()))))
    serve("topics_for_type", srv.TopicsForType, lambda r: srv.TopicsForType.Response(topics=[
        t for t, ty in zip(*graph.topics_and_types()) if types_ros2.load_message(ty) is _class(r.type,
                                                                                            types_ros2.load_message)]))
    serve("topic_type", srv.TopicType,
          lambda r: srv.TopicType.Response(type=dict(zip(*graph.topics_and_types())).get(r.topic, "")))
    serve("services", srv.Services, lambda r: srv.Services.Response(services=sorted(graph.services_and_types())))
    serve("services_for_type", srv.ServicesForType, lambda r: srv.ServicesForType.Response(services=sorted(
        s for s, ty in graph.services_and_types().items()
        if _class(ty, types_ros2.load_service) is _class(r.type, types_ros2.load_service))))
    serve("service_type", srv.ServiceType,
          lambda r: srv.ServiceType.Response(type=graph.services_and_types().get(r.service, "")))
    serve("service_node", srv.ServiceNode,
          lambda r: srv.ServiceNode.Response(node=(graph.service_providers(r.service) or [""])[0]))
    serve("service_providers", srv.ServiceProviders,
          lambda r: srv.ServiceProviders.Response(providers=graph.service_providers(r.service)))
    serve("nodes", srv.Nodes, lambda r: srv.Nodes.Response(nodes=graph.nodes()))
    serve("node_details", srv.NodeDetails, lambda r: srv.NodeDetails.Response(
        **dict(zip(("subscribing", "publishing", "services"), graph.node_details(r.node)))))
    serve("publishers", srv.Publishers, lambda r: srv.Publishers.Response(publishers=graph.endpoints(r.topic, True)))
    serve("subscribers", srv.Subscribers,
          lambda r: srv.Subscribers.Response(subscribers=graph.endpoints(r.topic, False)))
    serve("message_details", srv.MessageDetails, lambda r: srv.MessageDetails.Response(typedefs=details(r.type, "msg")))
    serve("service_request_details", srv.ServiceRequestDetails,
          lambda r: srv.ServiceRequestDetails.Response(typedefs=details(r.type, "Request")))
    serve("service_response_details", srv.ServiceResponseDetails,
          lambda r: srv.ServiceResponseDetails.Response(typedefs=details(r.type, "Response")))

    def get_param(r: Any) -> Any:
        value = params.get(r.name)
        return srv.GetParam.Response(value=r.default_value if value is None else json.dumps(value))

    serve("get_param", srv.GetParam, get_param)
    serve("set_param", srv.SetParam, lambda r: (params.set(r.name, r.value), srv.SetParam.Response())[1])
    serve("has_param", srv.HasParam, lambda r: srv.HasParam.Response(exists=params.get(r.name) is not None))
    serve("delete_param", srv.DeleteParam, lambda r: srv.DeleteParam.Response())  # ROS 2 nodes keep theirs
    serve("get_param_names", srv.GetParamNames, lambda r: srv.GetParamNames.Response(names=params.names(graph)))
    serve("get_time", srv.GetTime, lambda r: srv.GetTime.Response(time=node.get_clock().now().to_msg()))
    serve("get_ros_version", srv.GetROSVersion, lambda r: srv.GetROSVersion.Response(version=2, distro="jazzy"))
    serve("get_action_servers", srv.GetActionServers,
          lambda r: srv.GetActionServers.Response(action_servers=graph.action_servers()))

    def raw_types(r: Any) -> Any:
        topics, types = graph.topics_and_types()
        return srv.TopicsAndRawTypes.Response(topics=topics, types=types,
                                              typedefs_full_text=[full_text(t) for t in types])

    serve("topics_and_raw_types", srv.TopicsAndRawTypes, raw_types)
    executor = MultiThreadedExecutor(num_threads=4)
    executor.add_node(node)
    node.get_logger().info("rosapi ready")
    try:
        executor.spin()
    except KeyboardInterrupt:
        pass
    finally:
        executor.shutdown()
        node.destroy_node()
        rclpy.try_shutdown()


if __name__ == "__main__":
    main(sys.argv)
