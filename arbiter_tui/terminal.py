"""The same picture in fewer bytes: the console's terminal output with each style change said once.

Textual renders every styled run of a line as ``ESC[<the whole style>m text ESC[0m`` (``Strip.render``):
a reset after every run, then the next run's whole style again, although consecutive runs mostly share
their background and often their colour. Over SSH every byte is encrypted on the Pi and carried by the
link; at 200x60 the dashboard wrote 50 kB a second, 60 % of it these codes (docs/benchmarks/
screen-bytes.md), more than a 256 kbit/s link carries. :func:`fewer_sgr` rewrites one write of the
console so that the terminal is told only what changes between one run of text and the next: the cells
end up with the same characters and the same attributes (tests/unit/test_terminal.py checks it with a
terminal emulator, pyte, on the screens the console draws), and the terminal's state at the end of the
write is what the original left, so writes stay independent of each other.

What counts as text: anything that is not an escape sequence, ``\\r`` or ``\\n``; an erase (``ESC[K``,
``ESC[J``, ``ESC[X``: they paint with the current background) or any other sequence this module does not
know also gets the style the original had at that point first. A select-graphic-rendition code this module
cannot read (colon sub-parameters, a code it has no name for) is passed on as it came, and so is every
code after it, until a plain reset: never a guess. Pure: no Textual, no I/O.
"""

from __future__ import annotations

import logging
import re
from functools import lru_cache
from typing import Protocol, TypeVar

log = logging.getLogger(__name__)
_failed = False  # the rewrite raised once (said once in the log)

# (attributes bitmask, foreground, background, underline colour): each colour its SGR parameters as
# written ("31", "38;5;253", "38;2;1;2;3") or None for the terminal's default
State = tuple[int, str | None, str | None, str | None]
RESET: State = (0, None, None, None)

_ON = {1: 1, 2: 2, 3: 3, 4: 4, 5: 5, 6: 6, 7: 7, 8: 8, 9: 9, 21: 10, 51: 11, 52: 12, 53: 13}  # code -> bit
_CODE = {bit: code for code, bit in _ON.items()}
# an "off" code and the bits it clears (22 clears bold and dim alike; 24 both underlines)
_OFF = {22: (1, 2), 23: (3,), 24: (4, 10), 25: (5, 6), 27: (7,), 28: (8,), 29: (9,), 54: (11, 12), 55: (13,)}
_OFF_OF_BIT = {bit: code for code, bits in _OFF.items() for bit in bits}

# CSI (optionally private) or OSC (ended by BEL or ST); text is what lies between the matches
_SEQUENCE = re.compile(r"\x1b\[([0-9;:?<=>]*)[ -/]*([@-~])|\x1b\][^\x07\x1b]*(?:\x07|\x1b\\)|\x1b[^\[\]]")
_NO_PAINT = frozenset("HfABCDEFGdnhlsu")  # cursor moves, modes, reports: they paint no cell
# what shows on a blank cell besides its background: underlines, reverse, strike-through, frame, overline
_DRAWN_ON_BLANKS = sum(1 << bit for bit in (4, 7, 9, 10, 11, 12, 13))
_PLAIN = re.compile(r"[0-9;:]*")  # an SGR's parameters; anything else is a private sequence (">4;1m")


@lru_cache(maxsize=4096)
def apply(state: State, params: str) -> State | None:
    """``state`` after ``ESC[params m``; None when a parameter is not one this module can read."""
    if ":" in params:
        return None
    ps = params.split(";")
    attrs, fg, bg, ul = state
    i = 0
    while i < len(ps):
        n = int(ps[i]) if ps[i] else 0
        if n == 0:
            attrs, fg, bg, ul = RESET
        elif n in _ON:
            attrs |= 1 << _ON[n]
        elif n in _OFF:
            for bit in _OFF[n]:
                attrs &= ~(1 << bit)
        elif 30 <= n <= 37 or 90 <= n <= 97:
            fg = str(n)
        elif 40 <= n <= 47 or 100 <= n <= 107:
            bg = str(n)
        elif n in (39, 49, 59):
            fg, bg, ul = (None if n == 39 else fg), (None if n == 49 else bg), (None if n == 59 else ul)
        elif n in (38, 48, 58):
            width = {"5": 3, "2": 5}.get(ps[i + 1] if i + 1 < len(ps) else "", 0)
            if not width or i + width > len(ps) or not all(p.isdigit() for p in ps[i + 1 : i + width]):
                return None
            colour = ";".join(ps[i : i + width])
            fg, bg, ul = (colour if n == 38 else fg), (colour if n == 48 else bg), (colour if n == 58 else ul)
            i += width
            continue
        else:
            return None
        i += 1
    return attrs, fg, bg, ul


def _codes(state: State) -> list[str]:
    attrs, fg, bg, ul = state
    codes = [str(_CODE[bit]) for bit in sorted(_CODE) if attrs & (1 << bit)]
    return codes + [c for c in (fg, bg, ul) if c is not None]


@lru_cache(maxsize=4096)
def change(old: State, new: State) -> str:
    """The shortest SGR that takes a terminal from ``old`` to ``new`` (empty when they are equal)."""
    if old == new:
        return ""
    if new == RESET:
        return "\x1b[0m"
    whole = "\x1b[" + ";".join(["0", *_codes(new)]) + "m"
    removed, added = old[0] & ~new[0], new[0] & ~old[0]
    codes: list[str] = []
    for code in sorted({_OFF_OF_BIT[bit] for bit in _CODE if removed & (1 << bit)}):
        codes.append(str(code))
        added |= new[0] & sum(1 << bit for bit in _OFF[code])  # what the off code also cleared
    codes += [str(_CODE[bit]) for bit in sorted(_CODE) if added & (1 << bit)]
    for had, wants, default in zip(old[1:], new[1:], ("39", "49", "59"), strict=True):
        if had != wants:
            codes.append(default if wants is None else wants)
    step = "\x1b[" + ";".join(codes) + "m"
    return step if len(step) < len(whole) else whole


def _styled(text: str, shown: State, wanted: State, out: list[str]) -> State:
    """The style ``text`` is painted with, its change from ``shown`` appended to ``out``: ``wanted``, but
    for blanks only what a blank shows (its background, where nothing draws over it: no underline,
    reverse or strike-through), so that the gaps between a plot's points keep the points' colour."""
    if not text.strip(" \r\n") and not ((shown[0] | wanted[0]) & _DRAWN_ON_BLANKS):
        wanted = (shown[0], shown[1], wanted[2], shown[3])
    out.append(change(shown, wanted))
    return wanted


def fewer_sgr(data: str) -> str:
    """``data`` (one write of the console, which starts and ends with the terminal's style reset, as
    Textual's do) with each style change said once, before the text it styles."""
    if "\x1b[" not in data:
        return data
    out: list[str] = []
    shown = wanted = RESET  # what the terminal has; what the original would have by now
    verbatim = False  # after a code this module cannot read: everything as it came, up to a reset
    at = 0
    for m in _SEQUENCE.finditer(data):
        text = data[at : m.start()]
        at = m.end()
        if text:
            if shown != wanted and text.strip("\r\n"):
                shown = _styled(text, shown, wanted, out)
            out.append(text)
        final, params = m.group(2), m.group(1)
        if final == "m" and params is not None and _PLAIN.fullmatch(params):
            if verbatim or (new := apply(wanted, params)) is None:
                out.append(change(shown, wanted))  # what the original had when its code came
                out.append(m.group(0))  # (as it came; a reset ends the verbatim stretch)
                verbatim = params not in ("", "0")
                shown = wanted = RESET
                continue
            wanted = new
            continue
        if final is not None and final not in _NO_PAINT and shown != wanted:
            out.append(change(shown, wanted))  # an erase paints with the current background
            shown = wanted
        out.append(m.group(0))
    text = data[at:]
    if text and shown != wanted and text.strip("\r\n"):
        shown = _styled(text, shown, wanted, out)
    out.append(text)
    if shown != wanted and not verbatim:
        out.append(change(shown, wanted))  # the write ends in the state the original left
    return "".join(out)


class _Writes(Protocol):
    def write(self, data: str) -> None: ...


W = TypeVar("W", bound=_Writes)


def fewer_bytes(base: type[W]) -> type[W]:
    """``base`` (a terminal driver class) with every write passed through :func:`fewer_sgr`."""

    class FewerBytes(base):  # type: ignore[misc, valid-type]  # the driver class Textual chose at run time
        def write(self, data: str) -> None:
            try:
                shorter = fewer_sgr(data)
            except Exception:  # never a screen lost to this: the write as Textual made it, said once
                global _failed
                if not _failed:
                    _failed = True
                    log.exception("terminal output: written as it came (the rewrite failed)")
                shorter = data
            super().write(shorter)

    FewerBytes.__name__ = f"FewerBytes{base.__name__}"
    return FewerBytes
