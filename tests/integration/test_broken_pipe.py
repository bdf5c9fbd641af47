"""Output piped into a reader that leaves early (``| head``): every subcommand exits 1 quietly, as
command-line tools do, never with a BrokenPipeError traceback (issue 46, item 5)."""

from __future__ import annotations

import os
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest

from arbiter_tui.analytics.exports import to_csv

from ..support.backend import BackendProc, start_backend
from ..support.points import make_point

PIPE_CAPACITY = 64 * 1024  # Linux's default; the big outputs below are many times this


def cli(*args: str) -> list[str]:
    return [sys.executable, "-m", "arbiter_tui.cli", *args]


@pytest.fixture(scope="module")
def backend() -> Iterator[BackendProc]:
    b = start_backend("--autonomy")
    yield b
    b.stop()


@pytest.fixture(scope="module")
def files(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """A small export, and one of 2,000 runs whose `--by run` table is many pipes long."""
    d = tmp_path_factory.mktemp("exports")
    small, big = d / "small.csv", d / "big.csv"
    small.write_text(to_csv([make_point(i, "stanley", run=1) for i in range(50)]))
    big.write_text(to_csv([make_point(i, "stanley", run=1 + i // 2) for i in range(4000)]))
    return {"small": small, "big": big}


BIG = ["stats --by run (many pipes long)", "stats --by run --json (one long line)"]
CASES = {
    "stats": ["stats", "{small}"],
    "stats --by run (many pipes long)": ["stats", "{big}", "--by", "run"],
    "stats --by run --json (one long line)": ["stats", "{big}", "--by", "run", "--json"],
    "compare": ["compare", "--mission", "corner"],
    "compare --json": ["compare", "--mission", "corner", "--json"],
    "compare --latency (a sweep)": ["compare", "--latency", "0,100", "--mission", "corner"],
    "topics": ["topics", "--tracker", "{api}"],
    "autonomy status": ["autonomy", "status", "--tracker", "{api}"],
}


def _args(case: str, files: dict[str, Path], request: pytest.FixtureRequest) -> list[str]:
    api = request.getfixturevalue("backend").api if any("{api}" in a for a in CASES[case]) else ""
    return [a.format(api=api, **{k: str(v) for k, v in files.items()}) for a in CASES[case]]


@pytest.mark.parametrize("case", list(CASES))
def test_a_reader_gone_before_the_first_line_is_a_quiet_exit_1(case, files, request):
    """The pipe's reader has left before anything is written: the first write fails, always (no race),
    whether it comes mid-output or at the flush on the way out."""
    args = _args(case, files, request)
    r, w = os.pipe()
    os.close(r)
    try:
        done = subprocess.run(cli(*args), stdout=w, stderr=subprocess.PIPE, text=True, timeout=60)
    finally:
        os.close(w)
    assert (done.returncode, done.stderr) == (1, ""), done.stderr[-2000:]


@pytest.mark.parametrize("case", BIG)
def test_a_real_head_that_leaves_early_ends_it_quietly(case, files, request, tmp_path):
    """`arbiter-tui ... | head -c 100`, as a user types it: head takes its bytes and exits while the
    command still has more to write than the pipe holds, so its next write fails, every time."""
    args = _args(case, files, request)
    for _ in range(3):
        err = tmp_path / "stderr"
        with open(err, "wb") as err_file:
            writer = subprocess.Popen(cli(*args), stdout=subprocess.PIPE, stderr=err_file)
            reader = subprocess.Popen(["head", "-c", "100"], stdin=writer.stdout, stdout=subprocess.PIPE)
            assert writer.stdout is not None
            writer.stdout.close()  # the pipe is the writer's and head's alone: head leaving closes it
            head_out, _ = reader.communicate(timeout=60)
            writer.wait(timeout=60)
        assert len(head_out) == 100
        assert (writer.returncode, err.read_text()) == (1, ""), err.read_text()[-2000:]


@pytest.mark.parametrize("case", BIG)
def test_the_whole_output_is_bigger_than_a_pipe(case, files, request):
    """What makes the test above certain: the command had more to write than a pipe holds."""
    done = subprocess.run(cli(*_args(case, files, request)), capture_output=True, timeout=60)
    assert done.returncode == 0 and len(done.stdout) > 4 * PIPE_CAPACITY
