#!/usr/bin/env bash
# Runs every benchmark and appends each one's JSON line to bench/results.jsonl; then
# `python bench/report.py` turns that file into the table in docs/BENCHMARKS.md.
# SHORT=1 for the quick variants (what was run on the 2-core CI-class machine).
set -euo pipefail
cd "$(dirname "$0")/.."
PY=${PYTHON:-.venv/bin/python}
out=bench/results.jsonl
: > "$out"
if [ -n "${SHORT:-}" ]; then d=3; s=15; soak=300; else d=10; s=60; soak=3600; fi
"$PY" bench/bench_stats.py | tail -1 >> "$out"
"$PY" bench/latency.py --count 2000 --rate 100 | tail -1 >> "$out"
"$PY" bench/throughput.py --duration "$d" | tail -1 >> "$out"
"$PY" bench/api.py --duration 30 | tail -1 >> "$out"
"$PY" bench/tui.py --seconds "$s" | tail -1 >> "$out"
"$PY" bench/recovery.py --trials 5 | tail -1 >> "$out"
"$PY" bench/fuzz.py --count 10000 --seed 1 | tail -1 >> "$out"
"$PY" bench/soak.py --duration "$soak" | tail -1 >> "$out"
# the Pi-class CPU quota (cgroups): root only
if [ "$(id -u)" = 0 ]; then "$PY" bench/pi.py --seconds "$((s / 4 + 5))" | tail -1 >> "$out"; fi
