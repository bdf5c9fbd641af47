"""The session's journal (issue 55, "a dropped link loses nothing"): the real `arbiter-tui` in a real
terminal (tmux) against its embedded backend drives a mission, is killed (``kill -9``) or hung up on
(SIGHUP, as sshd does when the link drops), and what it recorded is on disk: ``arbiter-tui stats`` on
the journal gives the figures an export taken just before gave, and the next start offers the journal
and opens it on screen 2 with one key. Below them, the journal alone: a file cut anywhere reads up to
its last whole chunk, a clear starts a new file, an unwritable directory is one line and no journal."""

import json
import os
import shutil
import signal
import subprocess
import sys
import time
import uuid
from pathlib import Path

import pytest

from arbiter_tui.analytics.exports import ExportFormatError
from arbiter_tui.analytics.files import load_export
from arbiter_tui.analytics.model import stats_of_points
from arbiter_tui.analytics.store import AnalyticsStore, DataPoint
from arbiter_tui.session import journal_files as F
from arbiter_tui.session.journal import Journal, Sources

from ..support.waits import wait_for

ROOT = Path(__file__).resolve().parents[2]
tmux_missing = pytest.mark.skipif(shutil.which("tmux") is None, reason="tmux is not installed")


def tmux(*args: str) -> str:
    return subprocess.run(["tmux", *args], capture_output=True, text=True, timeout=10).stdout


def screen_until(session: str, *texts: str, timeout: float = 15.0) -> str:
    deadline = time.monotonic() + timeout
    out = ""
    while time.monotonic() < deadline:
        out = tmux("capture-pane", "-p", "-J", "-t", session)
        if all(t in out for t in texts):
            return out
        time.sleep(0.1)
    raise AssertionError(f"{texts!r} not on screen:\n{out}")


def launch(data: Path, export_dir: Path) -> str:
    """This checkout's `arbiter-tui` (embedded backend on free ports) in a new 120x40 tmux session, its
    user data directory ``data`` (the journal's home); the pane stays after it exits."""
    data.mkdir(exist_ok=True)
    session = f"journal-{uuid.uuid4().hex[:8]}"
    env = f"env PYTHONPATH={ROOT} XDG_DATA_HOME={data} XDG_CONFIG_HOME={data / 'config'}"
    cmd = (
        f"{env} {sys.executable} -m arbiter_tui.cli --bridge-port 0 --api-port 0 --export-dir {export_dir} "
        f"--log-file {data / 'console.log'}; sleep 30"
    )
    tmux("new-session", "-d", "-s", session, "-x", "120", "-y", "40", cmd)
    return session


def recorded(session: str) -> int:
    """The status line's count of samples recorded (``● REC 145``)."""
    line = tmux("capture-pane", "-p", "-t", session).splitlines()[:1]
    words = line[0].split() if line else []
    return int(words[words.index("REC") + 1]) if "REC" in words[:-1] else 0


def console_pid(session: str) -> int:
    shell = tmux("display-message", "-p", "-t", session, "#{pane_pid}").strip()
    found: list[str] = []

    def child() -> bool:
        found[:] = subprocess.run(["pgrep", "-P", shell], capture_output=True, text=True).stdout.split()
        return bool(found)

    wait_for(child, timeout=5)
    return int(found[0])


def gone(pid: int) -> bool:
    try:
        with open(f"/proc/{pid}/status") as fh:
            return "State:\tZ" in fh.read()
    except FileNotFoundError:
        return True


def stats(path: Path, *more: str) -> dict:
    out = subprocess.run(
        [sys.executable, "-m", "arbiter_tui.cli", "stats", str(path), "--json", *more],
        capture_output=True, text=True, timeout=60, env={**os.environ, "PYTHONPATH": str(ROOT)},
    )  # fmt: skip
    assert out.returncode == 0, out.stderr
    return json.loads(out.stdout)


def samples_in(path: Path) -> int:
    try:
        return len(load_export(path).points)
    except (ExportFormatError, OSError):
        return -1


@tmux_missing
@pytest.mark.parametrize("how", ["kill-9", "sighup"])
def test_a_killed_or_hung_up_console_loses_nothing_and_the_next_start_offers_it(tmp_path, how):
    data, exports = tmp_path / "data", tmp_path / "exports"
    exports.mkdir()
    session = launch(data, exports)
    again = None
    try:
        screen_until(session, "CONNECTED")
        pid = console_pid(session)
        journal_dir = data / "arbiter-tui" / "journal"
        (journal,) = list(journal_dir.glob("session_*.mcap"))  # written from the start
        tmux("send-keys", "-t", session, "a")  # manual -> a controller
        tmux("send-keys", "-t", session, "g")  # its mission
        screen_until(session, "(driving)")
        wait_for(lambda: recorded(session) >= 30, timeout=15)  # samples, a run, latency records
        tmux("send-keys", "-t", session, "Space")  # stopped: the run ends, no more samples
        screen_until(session, "Command  v +0.00 m/s  ω +0.00")
        tmux("send-keys", "-t", session, "2")
        tmux("send-keys", "-t", session, "C-s")
        tmux("send-keys", "-t", session, "j")  # JSON: what the store holds now
        wait_for(lambda: list(exports.glob("*.json")), timeout=10)
        (export,) = list(exports.glob("*.json"))
        want = samples_in(export)
        assert want > 10
        # journaled within a flush (0.5 s); the console still runs
        wait_for(lambda: samples_in(journal) == want, timeout=5)
        os.kill(pid, signal.SIGKILL if how == "kill-9" else signal.SIGHUP)
        wait_for(lambda: gone(pid), timeout=5)
        if how == "kill-9":
            assert not journal.read_bytes().endswith(b"\x89MCAP0\r\n")  # cut: no summary, no footer
        else:
            assert F.ending(journal) == "signal SIGHUP"  # finished on the way out, saying how
        # `stats` grades the journal with the figures the store had
        assert stats(journal) == stats(export)
        by_run = stats(journal, "--by", "run")
        assert by_run == stats(export, "--by", "run")
        assert [v["outcome"] for v in by_run.values() if "outcome" in v] == ["aborted"]
        # the next start says what it found, and R opens it on screen 2
        tmux("kill-session", "-t", session)
        again = launch(data, exports)
        screen_until(again, "did not end cleanly")
        tmux("send-keys", "-t", again, "R")
        screen_until(again, "FILE session_", f"samples {want} ", timeout=20)  # the journal on screen 2
    finally:
        tmux("kill-session", "-t", session)
        if again is not None:
            tmux("kill-session", "-t", again)


# -- the journal alone ---------------------------------------------------------------------------------
def _point(i: int, run: int | None) -> DataPoint:
    x, y, e_d = 0.05 * i, 0.01 * i * i, 0.02 * (i % 7)
    latency = 12.0 + i % 3
    return DataPoint(1.8e12 + 100 * i, x, y, 0.1, 0.5, 0.2, e_d, 0.01, "pure_pursuit", latency, run, i == 25)


def test_a_journal_cut_anywhere_reads_up_to_its_last_whole_chunk(tmp_path):
    store = AnalyticsStore(1000)
    store.start_collection()
    journal = Journal(Sources(store), tmp_path, 10**8, flush_s=3600)  # chunks only when stepped below
    journal.start()
    wait_for(lambda: journal._channels is not None, timeout=5)
    run = store.begin_run("pure_pursuit", "square", 1.8e12)
    sizes = []
    for chunk in range(4):
        for i in range(10 * chunk, 10 * chunk + 10):
            store.record(_point(i, run))
        with journal._lock:
            journal._step(force=True)  # the run's summary too (else at most every RUNS_EVERY_S)
        sizes.append(journal.path.stat().st_size)
    data = journal.path.read_bytes()
    journal.close()
    for chunk, size in enumerate(sizes):
        for cut in (size, size + 7, size + 100):  # whole; inside the next chunk's header; inside its data
            (tmp_path / "cut.mcap").write_bytes(data[:cut])
            got = load_export(tmp_path / "cut.mcap")
            assert len(got.points) == 10 * (chunk + 1), (chunk, cut)
            assert stats_of_points(got.points) == stats_of_points(store.points()[: 10 * (chunk + 1)])
            assert got.runs is not None and got.runs[0].stats.sampleCount == 10 * (chunk + 1)
            assert "a journal cut short" in got.notes[0]
    finished = load_export(journal.path)  # closed: read as any export, the run's last summary kept
    assert len(finished.points) == 40 and not finished.notes
    assert finished.runs is not None and [r.stats for r in finished.runs] == [r.stats for r in store.runs()]


def test_an_export_cut_short_is_still_refused(tmp_path):
    """Only a journal is read up to where it stops: a cut export is damaged, and said so."""
    from arbiter_tui.analytics.exports import to_mcap

    data = to_mcap([_point(i, None) for i in range(30)])
    (tmp_path / "x.mcap").write_bytes(data[: len(data) // 2])
    with pytest.raises(ExportFormatError, match="truncated MCAP"):
        load_export(tmp_path / "x.mcap")


def test_a_clear_starts_a_new_file_and_an_unwritable_directory_is_one_line(tmp_path):
    store = AnalyticsStore(1000)
    store.start_collection()
    said: list[str] = []
    journal = Journal(Sources(store), tmp_path, 10**8, warn=said.append, flush_s=0.05)
    journal.start()
    for i in range(5):
        store.record(_point(i, None))
    wait_for(lambda: journal.written == 5, timeout=5)
    first = journal.path
    store.clear()
    store.record(_point(6, None))
    wait_for(lambda: journal.written == 6, timeout=5)
    assert journal.path != first and F.ending(first) == F.CLEARED
    journal.close()
    assert len(load_export(first).points) == 5 and len(load_export(journal.path).points) == 1
    assert F.ending(journal.path) == F.QUIT and F.offerable(tmp_path) is None  # clean: nothing offered
    assert said == []

    blocked = tmp_path / "file"
    blocked.write_text("")
    journal = Journal(Sources(store), blocked / "journal", 10**8, warn=said.append, flush_s=0.05)
    journal.start()
    wait_for(lambda: said, timeout=5)
    journal.close()
    assert len(said) == 1 and said[0].startswith("no journal this session: ") and "\n" not in said[0]


def test_a_disk_that_takes_no_more_is_one_line_and_the_session_goes_on(tmp_path):
    """Writes that fail mid-session (here the kernel's file size limit, EFBIG, standing in for a full disk's
    ENOSPC: the same OSError from the same write): one line, the journal stops, the store records on, and
    what was journaled before still reads."""
    import resource

    store = AnalyticsStore(10_000)
    store.start_collection()
    said: list[str] = []
    journal = Journal(Sources(store), tmp_path, 10**8, warn=said.append, flush_s=0.05)
    journal.start()
    for i in range(20):
        store.record(_point(i, None))
    wait_for(lambda: journal.written == 20, timeout=5)
    soft, hard = resource.getrlimit(resource.RLIMIT_FSIZE)
    old = signal.signal(signal.SIGXFSZ, signal.SIG_IGN)  # a write past the limit fails instead of killing
    try:
        resource.setrlimit(resource.RLIMIT_FSIZE, (journal.path.stat().st_size + 4096, hard))
        for i in range(20, 2000):
            store.record(_point(i, None))
        wait_for(lambda: said, timeout=5)
    finally:
        resource.setrlimit(resource.RLIMIT_FSIZE, (soft, hard))
        signal.signal(signal.SIGXFSZ, old)
    journal.close()
    assert len(said) == 1 and said[0].startswith("journal stopped (File too large)"), said
    assert len(store) == 2000  # the session went on
    assert len(load_export(journal.path).points) >= 20  # cut where the disk stopped: read to its last chunk


def test_a_running_consoles_journal_is_never_offered_and_a_hung_up_one_once(tmp_path):
    store = AnalyticsStore(1000)
    store.start_collection()
    journal = Journal(Sources(store), tmp_path, 10**8, flush_s=0.05)
    journal.start()
    store.record(_point(0, None))
    wait_for(lambda: journal.written == 1, timeout=5)
    assert F.held(journal.path) and F.offerable(tmp_path) is None  # its console writes it: not lost
    journal.close("signal SIGHUP")
    found = F.offerable(tmp_path)
    assert found is not None and found.how == "signal SIGHUP" and found.path.name.endswith(".offered.mcap")
    assert F.offerable(tmp_path) is None  # once
    assert len(load_export(found.path).points) == 1
