"""The dispatch table: every op a client may send, and the room that handles it.

An op not here is answered with a ``status`` error (``unknown operation``). Server-to-client ops
(``status``, ``service_response``, ``png``, ``fragment``, and the frames a provider gets) are made
where they are sent. rosapi is not an op: it is the services ``call_service`` reaches (``rosapi.py``).
"""

from __future__ import annotations

from collections.abc import Callable

from .actions import ActionRoom
from .client import Client
from .frames import Frame
from .services import ServiceRoom
from .session import SessionRoom
from .topics import TopicRoom

Handler = Callable[[Client, Frame], None]  # raises BadFrame or MessageError: a status error to the client


def table(
    topics: TopicRoom, services: ServiceRoom, actions: ActionRoom, session: SessionRoom
) -> dict[str, Handler]:
    return {
        # topics.py
        "advertise": topics.advertise,
        "unadvertise": topics.unadvertise,
        "publish": topics.publish,
        "subscribe": topics.subscribe,
        "unsubscribe": topics.unsubscribe,
        # services.py (a provider's advertisements: providers.py)
        "call_service": services.call_service,
        "advertise_service": services.advertise_service,
        "service_response": services.service_response,
        "unadvertise_service": services.provided.unadvertise,
        # actions.py (a provider's advertisements: providers.py)
        "send_action_goal": actions.send_action_goal,
        "cancel_action_goal": actions.cancel_action_goal,
        "advertise_action": actions.advertise_action,
        "action_feedback": actions.action_feedback,
        "action_result": actions.action_result,
        "unadvertise_action": actions.provided.unadvertise,
        # session.py
        "auth": session.auth,
        "set_level": session.set_level,
    }
