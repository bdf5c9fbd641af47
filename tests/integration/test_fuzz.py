"""The fuzzer's deterministic subset against a real backend: every bad input answered or counted,
the valid command stream alongside recorded completely, the backend still serving afterwards."""

import json
import subprocess
import sys
from pathlib import Path

FUZZ = Path(__file__).resolve().parents[2] / "bench" / "fuzz.py"


def test_fuzz_subset_is_answered_counted_and_loses_no_valid_command():
    r = subprocess.run(
        [sys.executable, str(FUZZ), "--count", "1500", "--seed", "7", "--huge", "1"],
        capture_output=True,
        text=True,
        timeout=300,
    )
    result = json.loads(r.stdout.strip().splitlines()[-1])
    assert result["failures"] == [] and result["ok"] is True, result["failures"]
    assert r.returncode == 0
    assert result["cases"] == 1500
    kinds = result["by_kind"]
    for kind in (
        "bytes",
        "text",
        "truncated",
        "deep",
        "huge_number",
        "wrong_type",
        "bad_topic",
        "unknown_op",
    ):
        assert kinds[kind] > 20, kind
    assert kinds["frame_10MB"] == 1 and kinds["frame_over_transport_limit"] == 1
    assert sum(v for k, v in kinds.items() if k.startswith("http_")) == 1500 * 3 // 20
    assert sum(v for k, v in kinds.items() if k.startswith("envelope_")) == 1500 // 4
    assert result["valid_sent"] > 50 and result["valid_recorded"] == result["valid_sent"]
    assert result["rejected_envelopes"] > 200
