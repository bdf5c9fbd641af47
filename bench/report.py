#!/usr/bin/env python
"""bench/results.jsonl (bench/run_all.sh) -> the results table in docs/BENCHMARKS.md, between markers."""

from __future__ import annotations

import json
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
STATS_TARGETS = {1000: "< 0.1 ms", 100_000: "≥ 50x plain", 1_000_000: "< 30 ms"}
START, END = "<!-- results:start -->", "<!-- results:end -->"


def rows(results: list[dict]) -> list[str]:
    out = ["| benchmark | figure | value | target |", "|---|---|---|---|"]
    by = {r["bench"]: r for r in results}
    if s := by.get("stats"):
        for r in s["results"]:
            out.append(f"| bench_stats | AnalyticsStats, n={r['n']:,} | {r['stats_ms']:.3f} ms "
                       f"({r['speedup']:.0f}x plain Python) | {STATS_TARGETS.get(r['n'], '')} |")  # fmt: skip
        out.append(
            f"| bench_stats | memory per point | {s['results'][-1]['buffer_bytes_per_point']} B | ≤ 100 B |"
        )
        if runs := s.get("runs"):
            out.append(
                f"| bench_stats | nine stats of every run and algorithm, {runs['runs']} runs x "
                f"{runs['per_run']:,} samples, from scratch | {runs['all_runs_ms']:.1f} ms | ≤ 50 ms |"
            )
        for sc in s.get("screen", []):
            target = "≤ 20 ms (view)" if sc["n"] >= 1_000_000 else ""
            out.append(
                f"| bench_stats | analytics screen, {sc['n']:,} points: view built / update CPU / plots "
                f"redraw CPU (≤ 1/s) | {sc['view_ms']:.1f} / {sc['update_cpu_ms']:.1f} / "
                f"+{sc['plots_cpu_ms']:.1f} ms | {target} |"
            )
    latest = {r["transport"]: r for r in results if r["bench"] == "latency"}  # the newest run of each
    for lat in latest.values():
        tr = lat["transport"]
        out += [
            f"| latency ({tr}) | one-way p50 / p95 / p99 / max (ms) | {lat['one_way_p50_ms']} / "
            f"{lat['one_way_p95_ms']} / {lat['one_way_p99_ms']} / {lat['one_way_max_ms']} | |",
            f"| latency ({tr}) | round trip p50 / p95 / p99 (ms) | {lat['rtt_p50_ms']} / "
            f"{lat['rtt_p95_ms']} / {lat.get('rtt_p99_ms')} | |",
            f"| latency ({tr}) | TCP loopback floor p50 / p95 (ms) → one-way p50 / floor | "
            f"{lat['floor_p50_ms']} / {lat['floor_p95_ms']} → {lat['p50_over_floor']}x | embedded: ≤ 3x |",
            f"| latency ({tr}) | lost / negative | {lat['lost']} / {lat['negative']} | 0 |",
        ]
        if "dds_floor_p50_ms" in lat:
            out.append(
                f"| latency ({tr}) | DDS floor p50 / p95 (ms) → one-way p50, RTT p50 over it | "
                f"{lat['dds_floor_p50_ms']} / {lat['dds_floor_p95_ms']} → {lat['p50_over_dds_floor']}x, "
                f"{lat['rtt_p50_over_dds_floor']}x | ≤ 1.3x, ≤ 3x |"
            )
        if "plain_client_p99_ms" in lat:
            out.append(
                f"| latency ({tr}) | plain roslibpy script at 200 Hz (Nagle on, rejected envelopes mixed "
                f"in): p50 / p99 / max (ms) | {lat['plain_client_p50_ms']} / {lat['plain_client_p99_ms']} / "
                f"{lat['plain_client_max_ms']} | p99 ≤ 5 |"
            )
    if t := by.get("throughput"):
        out += [
            f"| throughput | max zero-loss rate, 1 client ({t['duration_s']} s trials) | "
            f"{t['one_client']['max_zero_loss_rate']:,}/s | ≥ 20,000/s |",
            f"| throughput | max zero-loss rate, 10 clients | "
            f"{t['ten_clients']['max_zero_loss_rate']:,}/s | |",
        ]
    if a := by.get("api"):
        out.append(f"| api | GET /api/latency p50 / p99, {a['records']:,} records, {a['pollers']} pollers "
                   f"at {a['rate_hz']} Hz | {a['p50_ms']} / {a['p99_ms']} ms | p99 ≤ 5 ms |")  # fmt: skip
    if u := by.get("tui"):
        t, b, r = u["arbiter_tui"], u["bare_textual"], u["ratios"]
        out.append(
            f"| tui | first frame: arbiter-tui / bare Textual app (median of {u['repeat']}) | "
            f"{t['first_frame_s']} / {b['first_frame_s']} s (+{u['first_frame_minus_bare_s']} s) "
            "| ≤ bare + 0.35 s |"
        )
        for key, label in (("control_key_held", "control, `i` held"), ("latency_screen", "latency screen"),
                           ("analytics_collecting", "analytics, mission running, collecting")):  # fmt: skip
            out.append(
                f"| tui | {label}: CPU, output (bare app) | {t[key]['cpu_percent_of_core']}% of a core, "
                f"{t[key]['kb_per_s']} KB/s ({b[key]['cpu_percent_of_core']}%, {b[key]['kb_per_s']} KB/s) "
                f"→ **{r[key]['cpu']}x, {r[key]['output']}x** | ≤ 1.5x, ≤ 1.5x |"
            )
    if f := by.get("fuzz"):
        http = sum(v for k, v in f["by_kind"].items() if k.startswith("http_"))
        env = sum(v for k, v in f["by_kind"].items() if k.startswith("envelope_"))
        out += [
            f"| fuzz | malformed cases (frames / envelopes / HTTP), seed {f['seed']} | {f['cases']:,} "
            f"({f['cases'] - http - env:,} / {env:,} / {http:,}) in {f['seconds']} s | ≥ 10,000 |",
            f"| fuzz | failures (unanswered, uncounted, 5xx, twist past limits) | {len(f['failures'])} | 0 |",
            f"| fuzz | valid 100 Hz stream alongside: recorded / sent | {f['valid_recorded']:,} / "
            f"{f['valid_sent']:,} | all |",
        ]
    if k := by.get("soak"):
        c, b = k["processes"]["console"], k["processes"]["backend"]
        out += [
            f"| soak | {k['duration_s'] / 60:g} min at {k['rate_hz']:g} Hz: lost / unreported of sent | "
            f"{k['lost']} / {k['unreported']} of {k['sent']:,} | 0 |",
            f"| soak | RSS console: start → end (growth) | {c['rss_start_mb']} → {c['rss_end_mb']} MB "
            f"({c['growth_mb']:+} MB) | ≤ 5 MB/h |",
            f"| soak | RSS backend: start → end (growth) | {b['rss_start_mb']} → {b['rss_end_mb']} MB "
            f"({b['growth_mb']:+} MB) | ≤ 5 MB/h |",
        ]
    if rc := by.get("recovery"):

        def fig(key: str) -> str:
            return f"{rc[key]['median_s']} / {rc[key]['max_s']} s"

        out += [
            f"| recovery | backend killed → link down, median / max of {rc['trials']} | "
            f"{fig('killed_to_disconnected')} | ≤ 1 s |",
            f"| recovery | backend back → CONNECTED | {fig('returned_to_connected')} | ≤ 3 s |",
            f"| recovery | CONNECTED → /odom flowing again | {fig('connected_to_odom')} | |",
            f"| recovery | silent link (no FIN) → noticed by the keep-alive | "
            f"{fig('silent_to_noticed')} | a few s |",
        ]
    if pi := by.get("pi"):
        fl = pi["floor"]
        out.append(
            f"| pi | {pi['quota_cores'] * 100:g} % quota, floor (plain roslibpy, 10 Hz): gap p50 / p95 / max "
            f"| {fl['gap_p50_ms']:.0f} / {fl['gap_p95_ms']:.0f} / {fl['gap_max_ms']:.0f} ms | |"
        )
        for name, c in pi["console"].items():
            out.append(
                f"| pi | {name} screen, mission driving: gap p50 / p95 / max · CPU of quota | "
                f"{c['gap_p50_ms']:.0f} / {c['gap_p95_ms']:.0f} / {c['gap_max_ms']:.0f} ms · "
                f"{c['cpu_percent_of_quota']:g} % | p95 ≤ 120, max ≤ 250 ms |"
            )
        k, r = pi["key_to_wire_console"], pi["key_to_wire_raw_tty"]
        out.append(
            f"| pi | key to wire p95: console / raw-tty script (n={k['n']}) | {k['p95_ms']:.1f} / "
            f"{r['p95_ms']:.1f} ms = {pi['key_to_wire_p95_ratio']}x | ≤ 3x |"
        )
    m = next((r.get("machine") for r in results if r.get("machine")), None)
    if m:
        out.append("")
        out.append(f"Machine: {m['cpus']} CPUs, {m['machine']}, Python {m['python']}; run on {m['date']}.")
    return out


def main() -> int:
    src = ROOT / "bench" / "results.jsonl"
    results = [json.loads(line) for line in src.read_text().splitlines() if line.strip()]
    doc = ROOT / "docs" / "BENCHMARKS.md"
    text = doc.read_text()
    block = "\n".join([START, *rows(results), END])
    if START in text:
        head, rest = text.split(START, 1)
        text = head + block + rest.split(END, 1)[1]
    else:
        text += "\n" + block + "\n"
    doc.write_text(text)
    print(block)
    return 0


if __name__ == "__main__":
    sys.exit(main())
