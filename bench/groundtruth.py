"""Every latency figure against injected ground truth, checked against issue 33's "Done means".

The backend runs under libfaketime (its wall clock shifted, drifting, or stepped mid-run); a loopback
proxy delays each direction of the console's link by a known amount (tests/support/delayproxy.py). The
console's own RosLink and LatencyMeter measure through it, 20 commands/s. The truth:

* rtt: forward + back (+ median jitter) + the base round trip (the same path with nothing injected,
  measured at the start of the same run);
* offset: what libfaketime was told, at each exchange's time; drift: its rate;
* one-way of each command: its raw figure (``t1 - t0``) minus the true offset (for the p50 checks:
  forward + half the base round trip, as loopback is symmetric).

The matrix: offset {0, +250 ms, -1.5 s} x delays {0/0, 20/5, 5/20, 50/50 ms} x drift {0, +500, -200 ppm}
(drift cases 31 s, the others 6 s), then half-normal jitter (10 ms, on the commands' direction, 31 s),
a 2 s stall, and a +100 ms clock step. A "window" is a second of the run: the figure shown at its end
(the live offset and its bound, the newest command's corrected one-way and its interval).

Criteria (a verdict each, then "N of M criteria met"):

1. rtt p50 within 1 ms of forward + back + base, every matrix case;
2. the injected jitter's p95 recovered within 10 % (corrected one-way p95 minus the jitter-free one-way,
   against the p95 of what the proxy drew);
3. a stall's commands counted lost, then late, exactly: each command whose report came after an expiry
   pass past its deadline, and no other; none lost at the end;
4. the offset's shown bound contains the true offset in >= 99 % of windows (all but the step case);
5. the corrected one-way's shown interval contains the true one-way in >= 99 % of windows (same cases);
6. with symmetric delays (0/0, 50/50) the corrected one-way p50 within 1 ms of the truth, drift or not;
7. drift within +-20 ppm of the injected rate after 30 s (every drift case and the jitter case);
8. a clock step detected once and the model re-anchored within 5 s, not averaged in (after it, every
   window's bound holds and the final offset is within 1 ms of the stepped truth).

With asymmetric paths the corrected one-way *cannot* be right (no round trip tells 20/5 from
12.5/12.5): there only the interval is the claim.

    .venv/bin/python bench/groundtruth.py [--quick] [--json]

--quick: one case of each kind (about 2.5 min instead of about 15).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from arbiter_core import stats
from tests.support.groundtruth import Case, Measured, faketime_available, measure

OFFSETS = [(0.0, "0"), (250.0, "+250ms"), (-1500.0, "-1.5s")]
DELAYS = [(0.0, 0.0), (20.0, 5.0), (5.0, 20.0), (50.0, 50.0)]
DRIFTS = [0.0, 500.0, -200.0]
DRIFT_S = 31.0  # the drift criterion is "after 30 s"
SHORT_S = 6.0  # no drift to learn: the offset, bounds and rtt need no more


def matrix() -> list[Case]:
    cases = []
    for off, off_name in OFFSETS:
        for drift in DRIFTS:
            for fwd, back in DELAYS:
                name = f"{off_name} {drift:+.0f}ppm {fwd:.0f}/{back:.0f}"
                cases.append(Case(name, offset_ms=off, drift_ppm=drift, forward_ms=fwd, back_ms=back,
                                  seconds=DRIFT_S if drift else SHORT_S))  # fmt: skip
    return cases


JITTER = Case("jitter |N(0,10)| fwd, +250ms 10/10", offset_ms=250, forward_ms=10, back_ms=10, jitter_ms=10,
              jitter_kind="halfnormal", jitter_back=False, seconds=DRIFT_S)  # fmt: skip
# the meter's lost_after_s of 1 s: a 2 s stall holds a second's commands past it
STALL = Case("stall 2 s, +250ms 5/5", offset_ms=250, forward_ms=5, back_ms=5, stall_s=2.0, stall_at_s=3.0,
             lost_after_s=1.0, seconds=8.0)  # fmt: skip
STEP = Case("step +100 ms, 5/5", step_ms=100, step_at_s=8, forward_ms=5, back_ms=5, seconds=16)
SPECIAL = [JITTER, STALL, STEP]


def quick() -> list[Case]:
    m = matrix()
    pick = {"-1.5s +500ppm 20/5", "+250ms +0ppm 50/50", "0 -200ppm 5/20"}
    return [c for c in m if c.name in pick] + SPECIAL


def row(m: Measured) -> dict:
    c = m.case
    drift_err = None if m.drift_ppm is None else m.drift_ppm - c.drift_ppm
    after = None
    if c.step_ms and m.stepped_at is not None and m.extra.get("reanchored_after_s") is not None:
        after = m.stepped_at + m.extra["reanchored_after_s"]
    nw, off_ok, ow_ok = m.windows(after=after)
    r = {
        "case": c.name,
        "n": m.matched,
        "rtt_err_ms": m.rtt_p50_ms - m.true_rtt_ms,
        "offset_err_ms": m.offset_error_ms,
        "offset_bound_ms": m.offset_bound_ms,
        "windows": nw,
        "offset_windows_ok": off_ok,
        "one_way_windows_ok": ow_ok,
        "drift_err_ppm": drift_err,
        "drift_bound_ppm": m.drift_bound_ppm,
        "one_way_err_ms": m.corrected_p50_ms - m.true_one_way_ms,
        "one_way_interval": [m.corrected_p50_lo_ms, m.corrected_p50_hi_ms],
        "true_one_way_ms": m.true_one_way_ms,
        "jitter_ms": m.jitter_ms,
        "raw_p50_ms": m.raw_p50_ms,
        "steps": m.extra.get("steps"),
        "reanchored_after_s": m.extra.get("reanchored_after_s"),
        "symmetric": c.forward_ms == c.back_ms and not c.jitter_ms,
        "drifting": bool(c.drift_ppm) or c is JITTER,
        "matrix": c not in SPECIAL,
        # main's meter on the same exchanges (min-RTT sample of 64 s, live correction, no bounds)
        "before_offset_err_ms": m.extra["before"][0] - m.true_offset_ms,
        "before_one_way_err_ms": m.extra["before"][1] - m.true_one_way_ms,
        "before_jitter_ms": m.extra["before"][2],
    }
    if c.jitter_ms:
        cor = [s.corrected_ms for s in m.samples]
        jitter_free = c.forward_ms + m.base_rtt_ms / 2
        r["jitter_p95_recovered_ms"] = stats.percentile(cor, 0.95) - jitter_free
        r["jitter_p95_injected_ms"] = stats.percentile(m.jitter_drawn_ms, 0.95)
    if c.stall_s:
        r["lost_then_late_expected"] = m.lost_then_late_expected()
        r["max_lost"], r["lost"], r["late"] = m.max_lost, m.lost, m.late
    return r


def yn(ok: bool | None) -> str:
    return "-" if ok is None else ("yes" if ok else "NO")


def fmt(v: float | None, spec: str) -> str:
    return "-" if v is None else format(v, spec)


def rtt_ok(r: dict) -> bool | None:
    return abs(r["rtt_err_ms"]) <= 1.0 if r["matrix"] else None


def sym_ok(r: dict) -> bool | None:
    return abs(r["one_way_err_ms"]) <= 1.0 if r["symmetric"] and r["matrix"] else None


def drift_ok(r: dict) -> bool | None:
    if not r["drifting"]:
        return None
    return r["drift_err_ppm"] is not None and abs(r["drift_err_ppm"]) <= 20.0


def print_table(rows: list[dict], base: float) -> None:
    head = (
        f"{'case':<36} {'n':>4} {'rtt err':>7} {'1':>3} {'off err':>8} {'± bound':>7} {'4 win':>6} "
        f"{'5 win':>6} {'1-way err':>9} {'6':>3} {'drift err':>9} {'± ppm':>6} {'7':>3}"
    )
    print(f"base round trip (nothing injected): {base:.3f} ms; errors are measured minus true, in ms")
    print(head)
    print("-" * len(head))
    for r in rows:
        nw = r["windows"]
        w4, w5 = f"{r['offset_windows_ok']}/{nw}", f"{r['one_way_windows_ok']}/{nw}"
        print(
            f"{r['case']:<36} {r['n']:>4} {r['rtt_err_ms']:>+7.3f} {yn(rtt_ok(r)):>3} "
            f"{r['offset_err_ms']:>+8.3f} {r['offset_bound_ms']:>7.3f} "
            f"{w4:>6} {w5:>6} "
            f"{r['one_way_err_ms']:>+9.3f} {yn(sym_ok(r)):>3} "
            f"{fmt(r['drift_err_ppm'], '+9.1f'):>9} {fmt(r['drift_bound_ppm'], '6.1f'):>6} "
            f"{yn(drift_ok(r)):>3}"
        )


def verdicts(rows: list[dict]) -> list[tuple[str, bool | None, str]]:
    """(criterion, met (None: not run), the figures)."""
    out: list[tuple[str, bool | None, str]] = []

    def over(pred, label: str) -> None:
        got = [pred(r) for r in rows]
        got = [g for g in got if g is not None]
        met = all(got) if got else None
        out.append((label, met, f"{sum(got)} of {len(got)} cases"))

    over(rtt_ok, "1 rtt p50 within 1 ms of forward + back + base")
    jit = [r for r in rows if "jitter_p95_injected_ms" in r]
    if jit:
        r = jit[0]
        rel = r["jitter_p95_recovered_ms"] / r["jitter_p95_injected_ms"] - 1.0
        out.append(("2 injected jitter's p95 recovered within 10 %", abs(rel) <= 0.10,
                    f"{r['jitter_p95_recovered_ms']:.2f} ms shown, {r['jitter_p95_injected_ms']:.2f} ms "
                    f"injected ({rel:+.1%})"))  # fmt: skip
    else:
        out.append(("2 injected jitter's p95 recovered within 10 %", None, "not run"))
    st = [r for r in rows if "lost_then_late_expected" in r]
    if st:
        r = st[0]
        exp = r["lost_then_late_expected"]
        ok = exp > 0 and r["max_lost"] == exp and r["late"] == exp and r["lost"] == 0
        out.append(("3 a stall's commands counted lost, then late, exactly", ok,
                    f"{exp} held past the deadline: {r['max_lost']} counted lost, {r['late']} late, "
                    f"{r['lost']} lost at the end"))  # fmt: skip
    else:
        out.append(("3 a stall's commands counted lost, then late, exactly", None, "not run"))
    bw = [r for r in rows if not r["case"].startswith("step")]
    nw = sum(r["windows"] for r in bw)
    for key, label in (
        ("offset_windows_ok", "4 offset bound holds the truth in >= 99 % of windows"),
        ("one_way_windows_ok", "5 one-way interval holds the truth in >= 99 % of windows"),
    ):
        k = sum(r[key] for r in bw)
        out.append((label, k >= 0.99 * nw if nw else None, f"{k} of {nw} windows ({k / max(nw, 1):.1%})"))
    over(sym_ok, "6 symmetric delays: corrected one-way p50 within 1 ms")
    over(drift_ok, "7 drift within ±20 ppm after 30 s")
    sp = [r for r in rows if r["case"].startswith("step")]
    if sp:
        r = sp[0]
        after = r["reanchored_after_s"]
        ok = (r["steps"] == 1 and after is not None and 0 <= after <= 5.0 and abs(r["offset_err_ms"]) <= 1.0
              and r["offset_windows_ok"] == r["windows"])  # fmt: skip
        out.append(("8 a clock step detected, re-anchored within 5 s, not averaged in", ok,
                    f"{r['steps']} step(s), re-anchored {fmt(after, '.2f')} s after it, final offset "
                    f"{r['offset_err_ms']:+.3f} ms off, bound held in {r['offset_windows_ok']} of "
                    f"{r['windows']} windows after"))  # fmt: skip
    else:
        out.append(("8 a clock step detected, re-anchored within 5 s, not averaged in", None, "not run"))
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="3 matrix cases + jitter, stall, step")
    ap.add_argument("--json", action="store_true", help="one JSON object per row as well")
    a = ap.parse_args(argv)
    if not faketime_available():
        print("groundtruth: libfaketime is not installed (apt-get install faketime)", file=sys.stderr)
        return 2
    started = time.monotonic()
    base = measure(Case("base", seconds=5)).rtt_p50_ms
    rows = []
    for case in quick() if a.quick else matrix() + SPECIAL:
        rows.append(row(measure(case, base)))
        if a.json:
            print(json.dumps(rows[-1]), flush=True)
    print_table(rows, base)
    print()
    results = verdicts(rows)
    for label, met, detail in results:
        print(f"{'MET' if met else ('-' if met is None else 'NOT MET'):>7}  {label}: {detail}")
    judged = [m for _l, m, _d in results if m is not None]
    print(f"{sum(judged)} of {len(judged)} criteria met ({time.monotonic() - started:.0f} s)")
    return 0 if all(judged) else 1


if __name__ == "__main__":
    sys.exit(main())
