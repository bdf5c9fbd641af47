"""The rosbridge v2 WebSocket endpoint (aiohttp) on either transport's topic bus.

``RosbridgeEndpoint`` (``endpoint.py``) takes the connections; each op a client sends goes through one
dispatch table to the room that handles it.
"""

from .client import CLIENT_QUEUE, LEVELS, MAX_CALLS, Client
from .endpoint import RosbridgeEndpoint, make_app
from .frames import MAX_FRAME_BYTES, TRANSPORT_MAX_FRAME, BadFrame
from .outbox import TOPIC_QUEUE, TOPIC_QUEUE_BYTES, TURN_BYTES, Fragments, Outbox, Payload
from .wire import DEAD_AFTER, WS_PING_S

__all__ = [
    "CLIENT_QUEUE",
    "DEAD_AFTER",
    "LEVELS",
    "MAX_CALLS",
    "MAX_FRAME_BYTES",
    "TOPIC_QUEUE",
    "TOPIC_QUEUE_BYTES",
    "TRANSPORT_MAX_FRAME",
    "TURN_BYTES",
    "WS_PING_S",
    "BadFrame",
    "Client",
    "Fragments",
    "Outbox",
    "Payload",
    "RosbridgeEndpoint",
    "make_app",
]
