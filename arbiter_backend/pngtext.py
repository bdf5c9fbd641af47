"""rosbridge's ``png`` compression: a frame's JSON text as the bytes of an RGB PNG image, base64-encoded.

As rosbridge_library's encoder lays it out (and roslibjs's ``decompressPng`` reads it back, three
characters a pixel): width ``floor(sqrt(n / 3))``, height ``ceil(n / 3 / width)``, the text padded with
``\\n`` (JSON whitespace) to fill the last pixels. Written with zlib and struct (no imaging library on
the robot for one image type); each row unfiltered (filter type 0), deflated at level 6.

Pure: no I/O.
"""

from __future__ import annotations

import base64
import math
import struct
import zlib

SIGNATURE = b"\x89PNG\r\n\x1a\n"
PAD = b"\n"


def _chunk(kind: bytes, data: bytes) -> bytes:
    return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))


def shape(n: int) -> tuple[int, int]:
    """(width, height) in pixels for ``n`` bytes of text (at least 1 x 1)."""
    width = max(1, math.floor(math.sqrt(n / 3.0)))
    height = max(1, math.ceil(n / 3.0 / width))
    return width, height


def encode_png(text: bytes) -> bytes:
    """The PNG image holding ``text`` (padded with ``\\n``)."""
    width, height = shape(len(text))
    row = width * 3
    padded = text + PAD * (row * height - len(text))
    raw = b"".join(b"\x00" + padded[y * row : (y + 1) * row] for y in range(height))
    header = struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)  # 8-bit RGB, no interlace
    return SIGNATURE + _chunk(b"IHDR", header) + _chunk(b"IDAT", zlib.compress(raw, 6)) + _chunk(b"IEND", b"")


def encode(text: str) -> str:
    """What a ``png`` frame's ``data`` holds for the JSON text ``text``."""
    return base64.b64encode(encode_png(text.encode("utf-8"))).decode("ascii")
