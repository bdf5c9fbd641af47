#!/usr/bin/env python
"""The table of ``bench/pi_table.sh``'s output: per size and screen, the before and after checkouts'
command gaps p95 / max, the share of gaps over 110 ms (where bench/pi.py printed it) and console CPU
(% of quota), medians over the runs; the worst max of each, and the after checkout's one-way latency
(how long a command was on its way once stamped, where bench/pi.py printed it).

    sudo bash bench/pi_table.sh BEFORE AFTER 3 > pi.jsonl && python bench/pi_table_summary.py pi.jsonl
"""

from __future__ import annotations

import argparse
import json
import statistics
from collections import defaultdict


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("results", help="the JSON lines bench/pi_table.sh printed")
    a = p.parse_args()
    rows: dict[tuple[str, str, str], list[dict]] = defaultdict(list)
    codes: list[str] = []
    with open(a.results) as f:
        for line in f:
            if not line.strip():
                continue
            entry = json.loads(line)
            code, result = entry["code"], entry["result"]
            if code not in codes:
                codes.append(code)
            for screen, figures in result["console"].items():
                rows[(result["size"], screen, code)].append(figures)
            rows[(result["size"], "floor", code)].append(result["floor"])
    before, after = codes[0], codes[-1]
    print(f"before: {before}  after: {after}")
    print("| size | screen | before p95 / max (ms) | after p95 / max (ms) | "
          "gaps > 110 ms before / after (%) | before CPU % | after CPU % | runs | worst max before / after | "
          "one-way p95 / max after (ms) |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    sizes = sorted({k[0] for k in rows}, key=lambda s: int(s.split("x")[0]))
    for size in sizes:
        for screen in dict.fromkeys(k[1] for k in rows if k[0] == size):
            b, a = rows[(size, screen, before)], rows[(size, screen, after)]

            def med(runs: list[dict], key: str, digits: int = 0) -> str:
                values = [r[key] for r in runs if r.get(key) is not None]
                return f"{statistics.median(values):.{digits}f}" if values else "—"

            def worst(runs: list[dict]) -> str:
                maxima = [r["gap_max_ms"] for r in runs if r.get("gap_max_ms") is not None]
                return f"{max(maxima):.0f}" if maxima else "—"

            print(f"| {size} | {screen} | {med(b, 'gap_p95_ms')} / {med(b, 'gap_max_ms')} | "
                  f"{med(a, 'gap_p95_ms')} / {med(a, 'gap_max_ms')} | "
                  f"{med(b, 'gaps_over_110_ms_percent', 1)} / {med(a, 'gaps_over_110_ms_percent', 1)} | "
                  f"{med(b, 'cpu_percent_of_quota')} | "
                  f"{med(a, 'cpu_percent_of_quota')} | {len(a)} | {worst(b)} / {worst(a)} | "
                  f"{med(a, 'one_way_p95_ms', 1)} / {med(a, 'one_way_max_ms', 1)} |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
