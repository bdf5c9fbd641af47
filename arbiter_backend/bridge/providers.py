"""What clients provide, by name, one provider per name endpoint-wide: one definition for services
(``advertise_service`` / ``unadvertise_service``) and actions (``advertise_action`` /
``unadvertise_action``).

A second advertisement of a name replaces the first provider, as rosbridge_server does, with a
``warning`` status to the client that advertised (if it asked for warnings with ``set_level``); what
was pending on the first fails with the reason. A provider that unadvertises or disconnects takes its
services and actions off the graph (ROS mode) and fails what waited on them.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from typing import Generic, Protocol, TypeVar

from ..provided import Sender
from . import frames
from .client import Client
from .frames import BadFrame, Frame

log = logging.getLogger(__name__)


class Provision(Protocol):
    """A provided service or action (``provided.ProvidedService``, ``provided.ProvidedAction``)."""

    name: str
    type_name: str
    provider: Sender
    withdraw: Callable[[], None] | None  # takes its rclpy server off the graph (ROS mode)

    def fail_all(self, reason: str) -> None: ...


P = TypeVar("P", bound=Provision)


class Providers(Generic[P]):
    def __init__(self, kind: str, name: Callable[[Frame, str], str] = frames.name) -> None:
        self.kind = kind  # "service" or "action": the frames' key for the name
        self.name = name  # the frame's name resolved (``Exposure.name``)
        self.noun = kind.capitalize()
        self.by_name: dict[str, P] = {}

    def __contains__(self, name: object) -> bool:
        return name in self.by_name

    def get(self, name: str) -> P | None:
        return self.by_name.get(name)

    def install(self, client: Client, frame: Frame, entry: P) -> None:
        """``entry`` (already on the graph in ROS mode) provides its name from now on."""
        old = self.by_name.get(entry.name)
        self.by_name[entry.name] = entry
        if old is not None:
            msg = (
                f"duplicate {self.kind} advertised: {entry.name} was provided by client {old.provider.id}; "
                "replaced"
            )
            log.warning("client %d: %s", client.id, msg)
            client.status("warning", msg, frame.get("id"))
            self.retire(old, f"{self.noun} {entry.name} was advertised again by another provider")
        log.info("client %d provides %s %s (%s)", client.id, self.kind, entry.name, entry.type_name)

    def retire(self, entry: P, reason: str) -> None:
        """``entry`` provides nothing any more: what waits on it fails with ``reason``."""
        if self.by_name.get(entry.name) is entry:
            del self.by_name[entry.name]
        entry.fail_all(reason)
        if entry.withdraw is not None:
            entry.withdraw()
            entry.withdraw = None

    def owned(self, client: Client, frame: Frame) -> P:
        """What the frame names (its ``service`` or ``action``), if ``client`` provides it."""
        name = self.name(frame, self.kind)
        entry = self.by_name.get(name)
        if entry is None or entry.provider is not client:
            raise BadFrame(f"{self.kind} {name} is not advertised by this client")
        return entry

    def unadvertise(self, client: Client, frame: Frame) -> None:
        """The op ``unadvertise_service`` / ``unadvertise_action``."""
        entry = self.owned(client, frame)
        self.retire(entry, f"{self.noun} {entry.name} was unadvertised")
        log.info("client %d no longer provides %s %s", client.id, self.kind, entry.name)

    def leave(self, client: Client) -> None:
        """``client`` is gone: what it provided goes with it."""
        for entry in [e for e in self.by_name.values() if e.provider is client]:
            self.retire(entry, f"{self.noun} {entry.name}: its provider disconnected")
