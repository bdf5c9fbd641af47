#!/usr/bin/env bash
# Every screen at 100x30 and 200x60 on a Pi-class quota, for two checkouts, RUNS times, alternating:
#   sudo bash bench/pi_table.sh /path/to/before-checkout /path/to/after-checkout [RUNS] > pi.jsonl
# Each line: {"code": CHECKOUT, "run": N, "result": <bench/pi.py's JSON>}. The sweep caches are warmed
# first (one analytics screen per checkout, long enough for the sweep to finish under the quota).
set -euo pipefail
cd "$(dirname "$0")/.."
PY=${PYTHON:-.venv/bin/python}
BEFORE=$1 AFTER=$2 RUNS=${3:-3}
for code in "$BEFORE" "$AFTER"; do
  "$PY" bench/pi.py --seconds 20 --size 100x30 --no-key-to-wire --screens analytics --pythonpath "$code" >/dev/null 2>&1
done
for run in $(seq "$RUNS"); do
  for size in 100x30 200x60; do
    for code in "$BEFORE" "$AFTER"; do
      r=$("$PY" bench/pi.py --seconds 12 --size "$size" --no-key-to-wire --pythonpath "$code" 2>&1 | tail -1)
      echo "{\"code\": \"$code\", \"run\": $run, \"result\": $r}"
    done
  done
done
