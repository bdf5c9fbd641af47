"""The CI-length soak: the console's loop at 100 Hz for 60 s against the backend (bench/soak.py --check).

ARBITER_SOAK_SECONDS changes the measured length (the one-hour figure comes from the script itself).
"""

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

SOAK = Path(__file__).resolve().parents[2] / "bench" / "soak.py"


@pytest.mark.slow
def test_soak_loses_nothing_and_memory_stays_flat():
    seconds = os.environ.get("ARBITER_SOAK_SECONDS", "60")
    r = subprocess.run(
        [
            sys.executable,
            str(SOAK),
            "--duration",
            seconds,
            "--max-records",
            "1000",
            "--max-points",
            "200",
            "--check",
        ],
        capture_output=True,
        text=True,
        timeout=float(seconds) + 180,
    )
    result = json.loads(r.stdout.strip().splitlines()[-1])
    assert result["sent"] >= 0.9 * 100 * (float(seconds) + result["warmup_s"])  # ~100 Hz really ran
    assert result["lost"] == 0 and result["unreported"] == 0, result
    for name in ("console", "backend"):
        assert result["processes"][name]["growth_mb"] <= 5.0, result["processes"]
    assert result["store_points"] == 200 and result["poll_failures"] == 0
    assert r.returncode == 0 and result["ok"] is True
