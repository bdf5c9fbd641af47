"""rosbridge's CBOR encodings (``compression: "cbor"`` / ``"cbor-raw"``) and CBOR frames from clients.

Out, as rosbridge_suite encodes them: one binary WebSocket frame holding the whole
envelope (``{op, topic, msg}``) as a CBOR map; in ``msg``, ``uint8[]``/``char[]``/``byte[]``
as CBOR byte strings and other numeric arrays as little-endian typed arrays tagged as
RFC 8746 says (``TYPED_ARRAY_TAGS``), bool arrays as arrays of booleans. ``cbor-raw``'s
``msg`` is ``{secs, nsecs, bytes}``: the message's CDR serialisation (with its 4-byte
encapsulation header) and the time it was received; only a transport that can
serialise (ROS mode) offers it.

Messages here are in rosbridge JSON form (the embedded bus): the types
``arbiter_core.msgtypes`` knows give the arrays their tags (Odometry's covariances
as float64 typed arrays; rosbridge itself cannot encode those fixed-size arrays),
other types go as they are. In ROS mode the transport converts from the ROS
message itself (``ros.convert.to_cbor``).

In: a binary frame whose first byte is a CBOR map's (0xa0..0xbf, never the first
byte of UTF-8 text) is a CBOR request. It is turned into rosbridge's JSON form
before anything else sees it: byte strings become base64 text (as ``uint8[]``
travels in JSON), typed arrays become lists of numbers; anything JSON cannot hold
(non-finite floats, other tags, undefined) is an error naming where it is.
"""

from __future__ import annotations

import base64
import io
import math
from typing import Any

import cbor2
import numpy as np

from arbiter_core.msgtypes import TYPES

# element type -> (tag, little-endian numpy dtype), RFC 8746 / rosbridge's cbor_conversion
TYPED_ARRAY_TAGS: dict[str, tuple[int, str]] = {
    "uint16": (69, "<u2"),
    "uint32": (70, "<u4"),
    "uint64": (71, "<u8"),
    "int8": (72, "i1"),
    "int16": (77, "<i2"),
    "int32": (78, "<i4"),
    "int64": (79, "<i8"),
    "float32": (85, "<f4"),
    "float64": (86, "<f8"),
}
_DTYPE_OF_TAG = {
    64: "u1",
    65: ">u2",
    66: ">u4",
    67: ">u8",
    68: "u1",
    69: "<u2",
    70: "<u4",
    71: "<u8",
    72: "i1",
    73: ">i2",
    74: ">i4",
    75: ">i8",
    77: "<i2",
    78: "<i4",
    79: "<i8",
    81: ">f4",
    82: ">f8",
    85: "<f4",
    86: "<f8",
}
MAX_DEPTH = 64


class CborError(ValueError):
    def __init__(self, msg: str, req_id: Any = None) -> None:
        super().__init__(msg)
        self.req_id = req_id  # the request's id, when the frame was a map with one


def typed_array(element: str, values: Any) -> cbor2.CBORTag:
    """``values`` (a list, array.array or numpy array) as the RFC 8746 typed array of ``element``."""
    tag, dtype = TYPED_ARRAY_TAGS[element]
    return cbor2.CBORTag(tag, np.asarray(values, dtype=dtype).tobytes())


def _from_spec(spec: Any, value: Any) -> Any:
    if isinstance(spec, dict) and isinstance(value, dict):
        return {k: _from_spec(spec[k], v) if k in spec else v for k, v in value.items()}
    if isinstance(spec, tuple) and isinstance(value, list):
        elem = spec[0]
        if elem in TYPED_ARRAY_TAGS and all(isinstance(v, (int, float)) for v in value):
            return typed_array(elem, value)
        return [_from_spec(elem, v) for v in value]
    return value


def values_of(type_name: str | None, msg: Any) -> Any:
    """The CBOR form of a message in rosbridge JSON form (typed arrays where its type is known)."""
    spec = TYPES.get(type_name or "")
    return msg if spec is None else _from_spec(spec, msg)


def encode(frame: dict[str, Any]) -> bytes:
    return cbor2.dumps(frame)


def is_cbor(data: bytes) -> bool:
    """A binary frame holding a CBOR map (its first byte is never the first byte of UTF-8 text)."""
    return bool(data) and 0xA0 <= data[0] <= 0xBF


def decode(data: bytes) -> dict[str, Any]:
    """A client's CBOR request in rosbridge JSON form; CborError naming what does not fit."""
    fp = io.BytesIO(data)
    try:
        obj = cbor2.CBORDecoder(fp, max_depth=MAX_DEPTH).decode()
    except (cbor2.CBORError, ValueError, RecursionError, MemoryError, OverflowError) as exc:
        raise CborError(f"invalid CBOR: {str(exc)[:200]}") from None
    if fp.tell() != len(data):
        raise CborError(f"invalid CBOR: {len(data) - fp.tell()} bytes after the first item")
    if not isinstance(obj, dict):
        raise CborError(f"a frame must be a CBOR map, got {type(obj).__name__}")
    req_id = obj.get("id")
    try:
        frame: dict[str, Any] = _to_json_form(obj, "frame", 0)
        return frame
    except CborError as exc:
        raise CborError(str(exc), req_id if isinstance(req_id, (str, int)) else None) from None


def _to_json_form(value: Any, path: str, depth: int) -> Any:
    if depth > MAX_DEPTH:
        raise CborError(f"{path}: nested too deeply")
    if value is None or isinstance(value, (bool, str)):
        return value
    if isinstance(value, int):
        return value
    if isinstance(value, float):
        if not math.isfinite(value):
            raise CborError(f"{path}: non-finite number {value} is not allowed")
        return value
    if isinstance(value, (bytes, bytearray)):
        return base64.b64encode(bytes(value)).decode("ascii")
    if isinstance(value, dict):
        out = {}
        for k, v in value.items():
            if not isinstance(k, str):
                raise CborError(f"{path}: map keys must be text, got {type(k).__name__}")
            out[k] = _to_json_form(v, f"{path}.{k}", depth + 1)
        return out
    if isinstance(value, (list, tuple)):
        return [_to_json_form(v, f"{path}[{i}]", depth + 1) for i, v in enumerate(value)]
    if isinstance(value, cbor2.CBORTag) and value.tag in _DTYPE_OF_TAG and isinstance(value.value, bytes):
        dtype = np.dtype(_DTYPE_OF_TAG[value.tag])
        if len(value.value) % dtype.itemsize:
            raise CborError(f"{path}: typed array of {len(value.value)} bytes is not whole elements")
        items = np.frombuffer(value.value, dtype=dtype).tolist()
        if dtype.kind == "f" and not all(math.isfinite(x) for x in items):
            raise CborError(f"{path}: non-finite number is not allowed")
        return items
    kind = f"tag {value.tag}" if isinstance(value, cbor2.CBORTag) else type(value).__name__
    raise CborError(f"{path}: {kind} has no rosbridge JSON form")
