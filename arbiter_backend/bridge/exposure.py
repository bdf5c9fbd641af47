"""What a client may reach: rosbridge_server's ``topics_glob`` / ``services_glob``, and our
``--actions-glob`` (goals sent and actions advertised). None: everything. And where a client's relative
names resolve: under the bridge node's namespace, as rosbridge_suite's node resolves them."""

from __future__ import annotations

from arbiter_core import topics as topics_mod

from ..topicwatch import TopicFilter
from .frames import BRIDGE_NODE_NAME, BadFrame, Frame, name


class Exposure:
    def __init__(
        self,
        topics: TopicFilter | None = None,
        services: TopicFilter | None = None,
        actions: TopicFilter | None = None,
        namespace: str = "",
        node: str = BRIDGE_NODE_NAME,
    ) -> None:
        self.topics = topics
        self.services = services
        self.actions = actions
        # the bridge node's namespace and name: a client's relative names resolve under them
        self.namespace = namespace
        self.node = node

    def name(self, frame: Frame, key: str = "topic") -> str:
        """The frame's topic, service or action name (``key``), resolved as rosbridge resolves it."""
        return name(frame, key, self.namespace, self.node)

    def resolve(self, given: str, what: str) -> str:
        """A name given in rosapi's arguments (a topic, service or node), resolved the same way;
        TopicNameError (a ValueError) says why it is not one."""
        return topics_mod.resolve(given, self.namespace, what=what, node=self.node)

    def topic_ok(self, topic: str) -> bool:
        return self.topics is None or self.topics.wants(topic)

    def service_ok(self, service: str) -> bool:
        return self.services is None or self.services.wants(service)

    def topic(self, frame: Frame) -> str:
        """The frame's ``topic``, checked against ``--topics-glob``."""
        topic = self.name(frame)
        if not self.topic_ok(topic):
            raise BadFrame(f"topic {topic} is not exposed by this server (--topics-glob)")
        return topic

    def action(self, frame: Frame) -> str:
        """The frame's ``action``, checked against ``--actions-glob``."""
        action = self.name(frame, "action")
        if self.actions is not None and not self.actions.wants(action):
            raise BadFrame(f"action {action} is not exposed by this server (--actions-glob)")
        return action
