"""Is this host's clock synchronised, and to what error? Parsing and the order of the probes (pure).

The probing itself (running ``chronyc``, ``timedatectl``, the ``adjtimex`` syscall) is the edges' (the
backend's ``hostclock``, the console's ``latency.hostclock``): they hand :func:`probe` two callables, so
everything here is tested on captured outputs. In order:

1. ``chronyc -c tracking`` (chrony): CSV; synchronised unless the leap status says "Not synchronised"
   or the reference is none; the error bound is chrony's own rule for the system clock,
   ``|system time offset| + root dispersion + root delay / 2``;
2. ``timedatectl show`` (systemd-timesyncd): ``NTPSynchronized=yes|no`` (the kernel's flag); the error
   from the kernel (3) when it can be read;
3. the kernel's NTP state (``adjtimex`` with no modes: read-only, no root): unsynchronised when the
   clock state is ``TIME_ERROR`` or ``STA_UNSYNC`` is set; ``esterror`` is the estimated error,
   ``maxerror`` the maximum (µs);
4. none of them answers: ``unknown`` (never an error).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

SOURCES = ("chrony", "timesyncd", "adjtimex", "unknown")
STA_UNSYNC = 0x0040
TIME_ERROR = 5
CHRONY_COMMAND = ("chronyc", "-c", "tracking")
TIMEDATECTL_COMMAND = ("timedatectl", "show")
PROBE_TIMEOUT_S = 1.0


@dataclass(frozen=True, slots=True)
class Adjtimex:
    """What ``adjtimex(2)`` says with no modes set: its return value and the fields used (µs)."""

    state: int
    status: int
    maxerror_us: int
    esterror_us: int


@dataclass(frozen=True, slots=True)
class TimeSync:
    source: str = "unknown"  # chrony | timesyncd | adjtimex | unknown
    synchronised: bool | None = None  # None: cannot tell
    offset_ms: float | None = None  # the system clock minus its reference (chrony only)
    error_ms: float | None = None  # the system clock is within this of true time (estimated)
    max_error_ms: float | None = None  # the kernel's maximum error, when read
    stratum: int | None = None
    reference: str | None = None
    detail: str | None = None  # why it is unknown, or what was not readable

    def to_dict(self) -> dict[str, Any]:
        return {
            "source": self.source,
            "synchronised": self.synchronised,
            "offset_ms": self.offset_ms,
            "error_ms": self.error_ms,
            "max_error_ms": self.max_error_ms,
            "stratum": self.stratum,
            "reference": self.reference,
            "detail": self.detail,
        }

    @classmethod
    def from_obj(cls, obj: object) -> TimeSync | None:
        """A ``time_sync`` block of ``/api/health``; None when it is absent or not one (an older backend)."""
        if not isinstance(obj, dict) or obj.get("source") not in SOURCES:
            return None
        sync = obj.get("synchronised")
        return cls(
            source=obj["source"],
            synchronised=sync if isinstance(sync, bool) else None,
            offset_ms=_num(obj.get("offset_ms")),
            error_ms=_num(obj.get("error_ms")),
            max_error_ms=_num(obj.get("max_error_ms")),
            stratum=obj.get("stratum") if isinstance(obj.get("stratum"), int) else None,
            reference=obj.get("reference") if isinstance(obj.get("reference"), str) else None,
            detail=obj.get("detail") if isinstance(obj.get("detail"), str) else None,
        )

    def short(self) -> str:
        """``chrony synchronised ±0.42 ms`` / ``adjtimex NOT synchronised`` / ``unknown``."""
        if self.source == "unknown":
            return "sync unknown"
        state = {True: "synchronised", False: "NOT synchronised", None: "sync ?"}[self.synchronised]
        err = "" if self.error_ms is None or not self.synchronised else f" ±{self.error_ms:.2f} ms"
        return f"{self.source} {state}{err}"


def _num(v: object) -> float | None:
    return float(v) if isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) else None


def parse_chronyc_tracking(text: str) -> TimeSync | None:
    """``chronyc -c tracking``: one CSV line (reference id, name, stratum, ref time, system time offset
    s, last offset, rms offset, frequency ppm, residual freq, skew, root delay s, root dispersion s,
    update interval, leap status). None when it is not that."""
    line = text.strip().splitlines()[0] if text.strip() else ""
    f = line.split(",")
    if len(f) < 14:
        return None
    try:
        stratum = int(f[2])
        system_s, root_delay_s, root_disp_s = float(f[4]), float(f[10]), float(f[11])
    except ValueError:
        return None
    leap = f[13].strip()
    ref_id = f[0].strip()
    synced = leap != "Not synchronised" and ref_id not in ("00000000", "0") and 0 < stratum < 16
    # chrony's own rule for the system clock: |offset| + root dispersion + root delay / 2
    error_s = abs(system_s) + root_disp_s + root_delay_s / 2.0
    # chronyc prints the offset as "slow" (positive: the clock is behind): ours is clock minus true
    return TimeSync(
        source="chrony",
        synchronised=synced,
        offset_ms=round(-system_s * 1000.0, 6),
        error_ms=round(error_s * 1000.0, 6),
        stratum=stratum,
        reference=f[1].strip() or ref_id,
        detail=None if synced else f"leap status {leap}",
    )


def parse_timedatectl_show(text: str) -> TimeSync | None:
    """``timedatectl show``: ``Key=value`` lines; None without ``NTPSynchronized``."""
    props = dict(line.split("=", 1) for line in text.splitlines() if "=" in line)
    flag = props.get("NTPSynchronized")
    if flag not in ("yes", "no"):
        return None
    detail = None if props.get("NTP", "yes") == "yes" else "NTP service off"
    return TimeSync(source="timesyncd", synchronised=flag == "yes", detail=detail)


def from_adjtimex(k: Adjtimex) -> TimeSync:
    """The kernel's NTP state."""
    synced = k.state != TIME_ERROR and not k.status & STA_UNSYNC
    return TimeSync(
        source="adjtimex",
        synchronised=synced,
        error_ms=k.esterror_us / 1000.0,
        max_error_ms=k.maxerror_us / 1000.0,
        detail=None if synced else "the kernel clock is marked unsynchronised (STA_UNSYNC)",
    )


def probe(run: Callable[[tuple[str, ...]], str | None], adjtimex: Callable[[], Adjtimex | None]) -> TimeSync:
    """Ask in order (module docstring). ``run`` returns a command's stdout, or None when it is missing,
    failed or timed out; ``adjtimex`` the kernel's state, or None where there is no such call."""
    out = run(CHRONY_COMMAND)
    chrony = None if out is None else parse_chronyc_tracking(out)
    if chrony is not None:
        return chrony
    kernel = adjtimex()
    out = run(TIMEDATECTL_COMMAND)
    timesyncd = None if out is None else parse_timedatectl_show(out)
    if timesyncd is not None:
        if kernel is not None:
            k = from_adjtimex(kernel)
            return TimeSync("timesyncd", timesyncd.synchronised, None, k.error_ms, k.max_error_ms,
                            detail=timesyncd.detail)  # fmt: skip
        return timesyncd
    if kernel is not None:
        return from_adjtimex(kernel)
    return TimeSync(detail="no chronyc, no timedatectl, no adjtimex")


def one_way_bound_ms(a: TimeSync | None, b: TimeSync | None) -> float | None:
    """How far apart two hosts' clocks can be when both say they are synchronised: the sum of their
    estimated errors. None unless both are synchronised with a known error."""
    if a is None or b is None or not a.synchronised or not b.synchronised:
        return None
    if a.error_ms is None or b.error_ms is None:
        return None
    return a.error_ms + b.error_ms
