"""Every latency figure against injected ground truth: a table, a row per case, the error of each figure.

The backend runs under libfaketime (its wall clock shifted, drifting, or stepped mid-run); a loopback
proxy delays each direction of the console's link by a known amount (tests/support/delayproxy.py). The
console's own RosLink and LatencyMeter measure through it. The truth:

* rtt: forward + back (+ mean jitter) + the base round trip (the same path with nothing injected);
* one-way: forward (+ mean jitter/2) + half the base round trip (loopback is symmetric);
* offset: what libfaketime was told, at the time of the estimate; drift: its rate.

Columns: rtt error; offset error, its bound, whether the bound holds; drift error (ppm) and its bound;
the corrected one-way p50's error and whether its interval holds the truth; jitter (on drift-corrected
figures); how fast a clock step was re-anchored. With asymmetric paths the corrected one-way *cannot*
be right (no round trip tells 20/5 from 12.5/12.5): there only the interval is the claim.

    .venv/bin/python bench/groundtruth.py [--quick] [--json]
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from tests.support.groundtruth import Case, Measured, faketime_available, measure

CASES = [
    Case("same clock, 10/10 ms", forward_ms=10, back_ms=10, seconds=10),
    Case("+250 ms, 10/10 ms", offset_ms=250, forward_ms=10, back_ms=10, seconds=10),
    Case("+250 ms, 20/5 ms (asym)", offset_ms=250, forward_ms=20, back_ms=5, seconds=10),
    Case("+250 ms, 10/10 ms, jitter 5", offset_ms=250, forward_ms=10, back_ms=10, jitter_ms=5, seconds=10),
    Case("-1.5 s +500 ppm, 5/5 ms", offset_ms=-1500, drift_ppm=500, forward_ms=5, back_ms=5, seconds=30),
    Case("-1.5 s +500 ppm, 20/5 ms", offset_ms=-1500, drift_ppm=500, forward_ms=20, back_ms=5, seconds=30),
    Case("+40 ms -200 ppm, 2/2 ms", offset_ms=40, drift_ppm=-200, forward_ms=2, back_ms=2, seconds=30),
    Case("0 then step +50 ms, 5/5", step_ms=50, step_at_s=8, forward_ms=5, back_ms=5, seconds=16),
]
QUICK = [CASES[2], CASES[4]]


def row(m: Measured) -> dict:
    drift_err = None if m.drift_ppm is None else m.drift_ppm - m.case.drift_ppm
    return {
        "case": m.case.name,
        "n": m.matched,
        "rtt_err_ms": m.rtt_p50_ms - m.true_rtt_ms,
        "offset_err_ms": m.offset_error_ms,
        "offset_bound_ms": m.offset_bound_ms,
        "offset_bound_holds": m.offset_bound_holds,
        "drift_err_ppm": drift_err,
        "drift_bound_ppm": m.drift_bound_ppm,
        "one_way_err_ms": m.corrected_p50_ms - m.true_one_way_ms,
        "one_way_interval": [m.corrected_p50_lo_ms, m.corrected_p50_hi_ms],
        "one_way_in_interval": m.one_way_in_interval,
        "true_one_way_ms": m.true_one_way_ms,
        "jitter_ms": m.jitter_ms,
        "raw_p50_ms": m.raw_p50_ms,
        "reanchored_after_s": m.extra.get("reanchored_after_s"),
        # main's meter on the same exchanges (min-RTT sample of 64 s, live correction, no bounds)
        "before_offset_err_ms": m.extra["before"][0] - m.true_offset_ms,
        "before_one_way_err_ms": m.extra["before"][1] - m.true_one_way_ms,
        "before_jitter_ms": m.extra["before"][2],
    }


def fmt(v: float | None, spec: str) -> str:
    return "-" if v is None else format(v, spec)


def print_table(rows: list[dict], base: float) -> None:
    head = (
        f"{'case':<30} {'n':>4} {'rtt err':>8} {'offset err':>10} {'± bound':>8} {'ok':>3} "
        f"{'drift err':>9} {'± ppm':>6} {'1-way err':>9} {'1-way interval':>17} {'ok':>3} "
        f"{'jitter':>7} {'step':>6}"
    )
    print(f"base round trip (nothing injected): {base:.3f} ms; errors are measured minus true, in ms")
    print(head)
    print("-" * len(head))
    for r in rows:
        lo, hi = r["one_way_interval"]
        step = r["reanchored_after_s"]
        step_text = "-" if step is None else f"{step:.2f}s"
        print(
            f"{r['case']:<30} {r['n']:>4} {r['rtt_err_ms']:>+8.3f} {r['offset_err_ms']:>+10.3f} "
            f"{r['offset_bound_ms']:>8.3f} {'yes' if r['offset_bound_holds'] else 'NO':>3} "
            f"{fmt(r['drift_err_ppm'], '+9.1f'):>9} {fmt(r['drift_bound_ppm'], '6.1f'):>6} "
            f"{r['one_way_err_ms']:>+9.3f} {f'[{lo:.2f}, {hi:.2f}]':>17} "
            f"{'yes' if r['one_way_in_interval'] else 'NO':>3} {r['jitter_ms']:>7.3f} "
            f"{step_text:>6}"
        )


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="the two cases the integration tests run")
    ap.add_argument("--json", action="store_true", help="one JSON object per row as well")
    a = ap.parse_args(argv)
    if not faketime_available():
        print("groundtruth: libfaketime is not installed (apt-get install faketime)", file=sys.stderr)
        return 2
    started = time.monotonic()
    base = measure(Case("base", seconds=5)).rtt_p50_ms
    rows = []
    for case in QUICK if a.quick else CASES:
        rows.append(row(measure(case, base)))
        if a.json:
            print(json.dumps(rows[-1]), flush=True)
    print_table(rows, base)
    print()
    print("the same exchanges through main's meter (offset from the min-RTT sample of 64 s, no bounds):")
    print(f"{'case':<30} {'offset err':>10} {'1-way err':>9} {'jitter':>7}")
    for r in rows:
        print(
            f"{r['case']:<30} {r['before_offset_err_ms']:>+10.3f} {r['before_one_way_err_ms']:>+9.3f} "
            f"{r['before_jitter_ms']:>7.3f}"
        )
    print(f"({time.monotonic() - started:.0f} s)")
    bad = [r["case"] for r in rows if not (r["offset_bound_holds"] and r["one_way_in_interval"])]
    if bad:
        print(f"BOUNDS BROKEN: {', '.join(bad)}", file=sys.stderr)
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
