"""rosapi node: serves /rosapi/* with the service types roslib and roslibpy call."""
from __future__ import annotations

from typing import Any, Callable

import roslib.message
import rospy

from rosapi import srv
from cell_nodes import priority
from . import graph


def main(argv: Any = None) -> None:
    rospy.init_node("rosapi", argv=argv)
    rospy.loginfo(priority.claim(priority.DEFERRABLE, "rosapi (graph queries)"))
    ns = "/rosapi/"

    def serve(name: str, srv_cls: type, fn: Callable[[Any], Any]) -> None:
        rospy.Service(ns + name, srv_cls, fn)

    def msg_details(type_name: str) -> Any:
        cls = roslib.message.get_message_class(type_name)
        if cls is None:
            raise rospy.ServiceException(f"unknown message type {type_name}")
        return graph.typedefs(cls)

    def srv_part(type_name: str, part: str) -> Any:
        cls = roslib.message.get_service_class(type_name)
        if cls is None:
            raise rospy.ServiceException(f"unknown service type {type_name}")
        return graph.typedefs(getattr(cls, part))

    serve("topics", srv.Topics, lambda r: srv.TopicsResponse(*graph.topics_and_types()))
    serve("topics_for_type", srv.TopicsForType, lambda r: srv.TopicsForTypeResponse(graph.topics_for_type(r.type)))
    serve("topic_type", srv.TopicType,
          lambda r: srv.TopicTypeResponse(dict(zip(*graph.topics_and_types())).get(r.topic, "")))
    serve("services", srv.Services, lambda r: srv.ServicesResponse(graph.services()))
    serve("services_for_type", srv.ServicesForType,
          lambda r: srv.ServicesForTypeResponse(graph.services_for_type(r.type)))
    serve("service_type", srv.ServiceType, lambda r: srv.ServiceTypeResponse(graph.service_type(r.service)))
    serve("service_node", srv.ServiceNode, lambda r: srv.ServiceNodeResponse(graph.service_node(r.service)))
    serve("service_host", srv.ServiceHost, lambda r: srv.ServiceHostResponse(graph.service_host(r.service)))
    serve("service_providers", srv.ServiceProviders,
          lambda r: srv.ServiceProvidersResponse([n for n in [graph.service_node(r.service)] if n]))
    serve("nodes", srv.Nodes, lambda r: srv.NodesResponse(graph.nodes()))
    serve("node_details", srv.NodeDetails, lambda r: srv.NodeDetailsResponse(*graph.node_details(r.node)))
    serve("publishers", srv.Publishers, lambda r: srv.PublishersResponse(graph.publishers(r.topic)))
    serve("subscribers", srv.Subscribers, lambda r: srv.SubscribersResponse(graph.subscribers(r.topic)))
    serve("message_details", srv.MessageDetails, lambda r: srv.MessageDetailsResponse(msg_details(r.type)))
    serve("service_request_details", srv.ServiceRequestDetails,
          lambda r: srv.ServiceRequestDetailsResponse(srv_part(r.type, "_request_class")))
    serve("service_response_details", srv.ServiceResponseDetails,
          lambda r: srv.ServiceResponseDetailsResponse(srv_part(r.type, "_response_class")))
    serve("get_param", srv.GetParam, lambda r: srv.GetParamResponse(graph.param_value_json(r.name, r.default)))
    serve("set_param", srv.SetParam, lambda r: (graph.set_param_json(r.name, r.value), srv.SetParamResponse())[1])
    serve("has_param", srv.HasParam, lambda r: srv.HasParamResponse(rospy.has_param(r.name)))
    serve("delete_param", srv.DeleteParam,
          lambda r: (rospy.delete_param(r.name) if rospy.has_param(r.name) else None, srv.DeleteParamResponse())[1])
    serve("search_param", srv.SearchParam, lambda r: srv.SearchParamResponse(rospy.search_param(r.name) or ""))
    serve("get_param_names", srv.GetParamNames, lambda r: srv.GetParamNamesResponse(graph.param_names()))
    serve("get_time", srv.GetTime, lambda r: srv.GetTimeResponse(rospy.get_rostime()))
    serve("get_action_servers", srv.GetActionServers,
          lambda r: srv.GetActionServersResponse(graph.action_servers()))

    def raw_types(r: Any) -> Any:
        topics, types = graph.topics_and_types()
        return srv.TopicsAndRawTypesResponse(topics, types, [graph.full_text(t) for t in types])

    serve("topics_and_raw_types", srv.TopicsAndRawTypes, raw_types)
    rospy.loginfo("rosapi ready")
    rospy.spin()
