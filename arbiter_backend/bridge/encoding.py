"""A subscription's ``publish`` frames in the encoding it asked for (``compression``), and split into
rosbridge ``fragment`` frames (``fragment_size``); each message encoded once per encoding for all the
clients that get it.

- ``none``: JSON text. In ROS mode the bus makes the JSON form on first use and marks ``uint8[]``
  base64 (``jsonframe``: a camera's base64 is spliced into the text, not scanned for escapes).
- ``png``: ``{"op": "png", "data": ...}``, that JSON text as an RGB image (``pngtext``).
- ``cbor``: a binary CBOR frame, ``uint8[]`` as bytes, numeric arrays as typed arrays (``cborenc``; in
  ROS mode from the ROS message, ``RosBus.cbor_values``).
- ``cbor-raw`` (ROS mode): ``{secs, nsecs, bytes}`` with the message's CDR bytes (``RosBus.cdr``).

Merged subscriptions take the strongest (``COMPRESSIONS``' order, as rosbridge). A JSON frame longer
than ``fragment_size`` goes out as ``fragment`` frames (``{op, id, data, num, total}``, ``id`` unique
per message); CBOR frames are not fragmented.
"""

from __future__ import annotations

import itertools
from typing import Any

from arbiter_core.msgtypes import MessageError

from .. import cborenc, jsonframe, pngtext
from ..bus import Bus, ConvertingBus
from .frames import dumps
from .outbox import Fragments, Payload

COMPRESSIONS = (
    "none",
    "png",
    "cbor",
    "cbor-raw",
)  # weakest first (ROSBRIDGE_PROTOCOL.md: cbor-raw beats cbor beats png beats none)
MIN_FRAGMENT = 64  # the smallest fragment_size taken (smaller would be a frame per few characters)


class Encoder:
    """The last frame made of each (topic, encoding), reused while the message is the same one."""

    def __init__(self, bus: Bus) -> None:
        self.bus = bus
        # the ROS transport's bus: its own JSON, CBOR and CDR forms (decided once: isinstance on a protocol
        # is slow for a per-message path)
        self.converting: ConvertingBus | None = bus if isinstance(bus, ConvertingBus) else None
        # (topic, encoding) -> (the last message, its frame); (topic, "fragments:<size>") -> (the last
        # message, its parts)
        self._encoded: dict[tuple[str, str], tuple[Any, Payload]] = {}
        self._fragmented: dict[tuple[str, str], tuple[Any, list[str]]] = {}
        self._fragment_ids = itertools.count(1)

    @property
    def serialises(self) -> bool:
        """The bus has each message's CDR bytes (``cbor-raw``): the ROS transport."""
        return self.converting is not None

    def encode(
        self, topic: str, compression: str, type_name: str | None, msg: dict[str, Any], fragment_size: int
    ) -> Payload | Fragments:
        """The ``publish`` frame of ``msg`` in ``compression``; a JSON one longer than ``fragment_size``
        (0: none) as ``fragment`` frames."""
        frame = self._publish_frame(topic, compression, type_name, msg)
        if fragment_size and isinstance(frame, str) and len(frame) > fragment_size:
            return self._fragments(topic, fragment_size, msg, frame)
        return frame

    def _publish_frame(
        self, topic: str, encoding: str, type_name: str | None, msg: dict[str, Any]
    ) -> Payload:
        """JSON text, a ``png`` frame holding that text as an image (``pngtext``), or a binary CBOR frame
        (``cborenc``)."""
        key = (topic, encoding)
        cached = self._encoded.get(key)
        if cached is not None and cached[0] is msg:
            return cached[1]
        frame: Payload
        if encoding in ("none", "png"):  # ROS mode: the JSON form is made on first use (ros/bus.py)
            if self.converting is None:  # the embedded bus: no ROS converter, so no base64 to splice
                text = dumps({"op": "publish", "topic": topic, "msg": msg})
            else:  # a camera's base64 spliced in, not scanned for escapes
                text = jsonframe.dumps(
                    {"op": "publish", "topic": topic, "msg": self.converting.json_form(msg)}
                )
        if encoding == "none":
            frame = text
        elif encoding == "png":
            frame = dumps({"op": "png", "data": pngtext.encode(text)})
        elif encoding == "cbor":
            convert = cborenc.values_of if self.converting is None else self.converting.cbor_values
            frame = cborenc.encode({"op": "publish", "topic": topic, "msg": convert(type_name, msg)})
        else:  # cbor-raw: the CDR bytes and the time received (subscribe checked ``serialises``)
            if self.converting is None:
                raise MessageError("cbor-raw needs the ROS transport's CDR bytes")
            raw, received_ns = self.converting.cdr(type_name, msg)
            secs, nsecs = divmod(received_ns, 1_000_000_000)
            frame = cborenc.encode(
                {"op": "publish", "topic": topic, "msg": {"secs": secs, "nsecs": nsecs, "bytes": raw}}
            )
        self._encoded[key] = (msg, frame)
        return frame

    def _fragments(self, topic: str, size: int, msg: dict[str, Any], frame: str) -> Fragments:
        """``frame`` as rosbridge ``fragment`` frames of ``size`` characters of its text, under an id of
        its own (made once per message and size for all the clients that get it)."""
        key = (topic, f"fragments:{size}")
        cached = self._fragmented.get(key)
        if cached is not None and cached[0] is msg:
            return Fragments(cached[1])
        frag_id = f"{topic}#{next(self._fragment_ids)}"
        total = -(-len(frame) // size)
        parts = [
            dumps(
                {
                    "op": "fragment",
                    "id": frag_id,
                    "data": frame[i * size : (i + 1) * size],
                    "num": i,
                    "total": total,
                }
            )
            for i in range(total)
        ]
        self._fragmented[key] = (msg, parts)
        return Fragments(parts)

    def forget(self, topic: str) -> None:
        """No client subscribes to ``topic`` any more: its last frames (a camera's: megabytes) go."""
        for key in [k for k in self._encoded if k[0] == topic]:
            del self._encoded[key]
        for key in [k for k in self._fragmented if k[0] == topic]:
            del self._fragmented[key]
