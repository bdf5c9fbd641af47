"""The rosbridge v2 WebSocket endpoint (aiohttp), on either transport's bus, in rooms:

- ``endpoint.py``: ``RosbridgeEndpoint``, the connections: frames in (JSON or CBOR), out through
  each client's writer, a client's state dropped when it goes.
- ``ops.py``: the dispatch table, every op a client may send and the room that handles it.
- ``topics.py``: advertise, unadvertise, publish, subscribe, unsubscribe (and throttling).
- ``services.py``: call_service, advertise_service, service_response, unadvertise_service.
- ``actions.py``: send_action_goal, cancel_action_goal, advertise_action, action_feedback,
  action_result, unadvertise_action.
- ``session.py``: auth, set_level.
- ``providers.py``: one provider per service or action name (advertise, replace, retire), for both.
- ``encoding.py``: a subscription's frames as JSON, png, cbor, cbor-raw, and in fragments.
- ``exposure.py``: what a client may reach (--topics-glob, --services-glob, --actions-glob).
- ``wire.py``: the socket: the writer task, liveness pings, TCP options.
- ``client.py``, ``outbox.py``: a client's state and its queues; ``frames.py``: field checks.

rosapi is the services ``call_service`` reaches (``arbiter_backend/rosapi.py``); pacing a slow client's
big frames is ``arbiter_backend/pacing.py``; what clients provide is ``arbiter_backend/provided.py``.
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
