"""What a client's frame holds: its JSON decoded, its fields checked (pure, no state).

Every check raises :class:`BadFrame` naming the field; the dispatcher answers it with a ``status``
error echoing the request's ``id`` and the connection stays open.
"""

from __future__ import annotations

import json
import re
from typing import Any, Literal, TypeVar, overload

from arbiter_core import topics

from .. import jsonframe

MAX_FRAME_BYTES = 1024 * 1024  # answered with a status error above this
TRANSPORT_MAX_FRAME = 16 * 1024 * 1024  # aiohttp closes the socket (1009) above this
BRIDGE_NODE_NAME = topics.BRIDGE_NODE  # the bridge's node (ROS mode); ``~`` names resolve under it
INTERFACE_TYPE = re.compile(r"([A-Za-z][A-Za-z0-9_]*)/(?:(srv|action)/)?([A-Za-z][A-Za-z0-9_]*)", re.ASCII)

Frame = dict[str, Any]

dumps = jsonframe.compact  # the endpoint's own frames (status, replies): no spaces, no NaN


class BadFrame(ValueError):
    pass


def _reject_constant(token: str) -> Any:
    raise BadFrame(f"non-finite number {token} is not allowed")


DECODER = json.JSONDecoder(parse_constant=_reject_constant)  # made once: json.loads(kw) makes one per call


_T = TypeVar("_T")


@overload
def field(frame: Frame, name: str, kind: type[_T], required: Literal[True] = True) -> _T: ...
@overload
def field(frame: Frame, name: str, kind: type[_T], required: bool) -> _T | None: ...
@overload
def field(frame: Frame, name: str, kind: tuple[type, ...], required: bool = True) -> Any: ...
def field(frame: Frame, name: str, kind: type | tuple[type, ...], required: bool = True) -> Any:
    """``frame[name]`` if it is a ``kind`` (a bool only where ``kind`` names bool); None when absent and
    not ``required``."""
    if name not in frame:
        if required:
            raise BadFrame(f"missing field {name!r}")
        return None
    value = frame[name]
    if isinstance(value, bool) and bool not in (kind if isinstance(kind, tuple) else (kind,)):
        raise BadFrame(f"field {name!r} has the wrong type (bool)")
    if not isinstance(value, kind):
        raise BadFrame(f"field {name!r} has the wrong type ({type(value).__name__})")
    return value


def name(frame: Frame, key: str = "topic", ns: str = "", node: str = BRIDGE_NODE_NAME) -> str:
    """A topic, service or action name (``key``) resolved as rosbridge_suite's node resolves it (rclpy:
    relative names under the bridge node's namespace ``ns``, ``~`` its own name ``node``), with
    ``arbiter_core.topics.resolve``: the one resolver."""
    given = field(frame, key, str)
    if not given or len(given) > 256:
        raise BadFrame(f"{key} must be a non-empty string of at most 256 characters")
    try:
        return topics.resolve(given, ns, what=key, node=node)
    except topics.TopicNameError as exc:
        raise BadFrame(f"invalid {key} name {json.dumps(given[:60])}: {exc}") from None


def interface_type(frame: Frame, key: str, kind: str, interfaces: Any) -> str:
    """A service (``kind`` srv) or action type, as ``pkg/<kind>/Name``: installed here in ROS mode
    (``interfaces`` given); in the embedded transport any well-formed name (values then pass through
    unchecked)."""
    given = field(frame, key, str)
    m = INTERFACE_TYPE.fullmatch(given)
    if m is None or m.group(2) not in (None, kind):
        raise BadFrame(f"invalid {kind} type name {given[:80]!r}: pkg/{kind}/Name or pkg/Name")
    if interfaces is not None:
        check = interfaces.service_type if kind == "srv" else interfaces.action_type
        return str(check(given))
    return f"{m.group(1)}/{kind}/{m.group(3)}"
