"""The bridge's ROS side for this process's generation (generation.py): the names every capability uses.

Both plumbing_ros1 and plumbing_ros2 offer: TopicHub, PublisherRegistry (shared.py's, bound to their client
library), SharedMessage, resolve_topic, call_service, serve, other_providers, send_action_goal, ServiceFailure,
TopicError, ServiceCallError, ActionGoalError, and the graph (topic_types).
"""
from __future__ import annotations

from .generation import ROS_VERSION

if ROS_VERSION == 2:
    from .plumbing_ros2 import (PublisherRegistry, ServiceFailure, TopicHub, call_service, other_providers,
                                resolve_topic, send_action_goal, serve)
else:
    from .plumbing_ros1 import (PublisherRegistry, ServiceFailure, TopicHub, call_service,  # type: ignore[assignment]
                                other_providers, resolve_topic, send_action_goal, serve)
from .shared import ActionGoalError, ServiceCallError, SharedMessage, TopicError

__all__ = ["PublisherRegistry", "ServiceFailure", "TopicHub", "call_service", "other_providers", "resolve_topic",
           "send_action_goal", "serve", "ActionGoalError", "ServiceCallError", "SharedMessage", "TopicError"]
