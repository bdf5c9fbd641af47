"""The session's journal (issue 55, "a dropped link loses nothing"): the real `arbiter-tui` in a real
terminal (tmux) against its embedded backend drives a mission, is killed (``kill -9``) or hung up on
(SIGHUP, as sshd does when the link drops), and what it recorded is on disk: ``arbiter-tui stats`` on
the journal gives the figures an export taken just before gave, and the next start offers the journal
and opens it on screen 2 with one key. Below them, the journal alone: a file cut anywhere reads up to
its last whole chunk, a clear starts a new file, an unwritable directory is one line and no journal."""

import errno
import json
import os
import shutil
import signal
import subprocess
import sys
import threading
import time
import uuid
from pathlib import Path

import numpy as np
import pytest

from arbiter_tui.analytics.exports import ExportFormatError
from arbiter_tui.analytics.files import load_export
from arbiter_tui.analytics.model import stats_of_points
from arbiter_tui.analytics.store import AnalyticsStore, DataPoint
from arbiter_tui.session import journal_files as F
from arbiter_tui.session.journal import Journal, Sources
from arbiter_tui.session.recording import open_recording

from ..support.tmux import new_session, tmux
from ..support.tmux import screen_until as _screen_until
from ..support.waits import wait_for

ROOT = Path(__file__).resolve().parents[2]
tmux_missing = pytest.mark.skipif(shutil.which("tmux") is None, reason="tmux is not installed")


def screen_until(session: str, *texts: str, timeout: float = 15.0) -> str:
    """The screen once all ``texts`` are on it, wrapped lines read as one."""
    return _screen_until(session, *texts, timeout=timeout, join=True)


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
    new_session(session, 120, 40, cmd)
    return session


def recorded(session: str) -> int:
    """The status line's count of samples recorded (``● REC 145``)."""
    return recorded_in(tmux("capture-pane", "-p", "-t", session))


def recorded_in(screen: str) -> int:
    """The count of samples recorded on a screen's status line (its first), 0 when it shows none."""
    line = screen.splitlines()[:1]
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
        wait_for(lambda: list(journal_dir.glob("session_*.mcap")), timeout=10)  # its own thread makes it
        (journal,) = list(journal_dir.glob("session_*.mcap"))  # written from the start
        tmux("send-keys", "-t", session, "a")  # manual -> a controller
        tmux("send-keys", "-t", session, "g")  # its mission
        screen_until(session, "(driving)")
        wait_for(lambda: recorded(session) >= 30, timeout=15)  # samples, a run, latency records
        tmux("send-keys", "-t", session, "Space")  # stopped: the run ends, no more samples
        screen_until(session, "Command  v +0.00 m/s  ω +0.00")
        # the robot standing gives one more sample (outside the run) a tick after the stop: the export
        # below must hold it too, so what is recorded has held still for a second first
        counts: list[tuple[float, int]] = []

        def held_still() -> bool:
            counts.append((time.monotonic(), recorded(session)))
            recent = {n for t, n in counts if t >= counts[-1][0] - 1.0}
            return counts[-1][0] - counts[0][0] >= 1.0 and len(recent) == 1

        wait_for(held_still, timeout=10, interval=0.1)
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
    first = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]])
    replan = np.array([[0.5, 0.0], [0.5, 2.0]])
    run = store.begin_run("pure_pursuit", "square", 1.8e12, path=first)
    sizes = []
    for chunk in range(4):
        if chunk == 2:
            store.follow_path(replan)  # the plans: the run's first reference, then a replan
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
            assert [(p.run_id, p.xy) for p in got.plans] == [(run, _xy(first)), (run, _xy(replan))][
                : 1 + (chunk >= 2)
            ]
    finished = load_export(journal.path)  # closed: read as any export, the run's last summary kept
    assert len(finished.points) == 40 and not finished.notes
    assert finished.runs is not None and [r.stats for r in finished.runs] == [r.stats for r in store.runs()]
    assert [(p.run_id, p.xy) for p in finished.plans] == [(run, _xy(first)), (run, _xy(replan))]
    view = open_recording(journal.path)  # the file view (screen 2's f, R) says them
    assert view.plans == 2


def _xy(path: np.ndarray) -> tuple[tuple[float, float], ...]:
    return tuple((float(x), float(y)) for x, y in path)


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


class Filling:
    """A journal's file on a disk that fills up when told: its writes fail as a full disk's do (ENOSPC)."""

    def __init__(self, stream) -> None:
        self.stream = stream
        self.full = False

    def write(self, data) -> int:
        if self.full:
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        return self.stream.write(data)

    def __getattr__(self, name):
        return getattr(self.stream, name)


def test_a_disk_that_takes_no_more_is_one_line_and_the_session_goes_on(tmp_path, monkeypatch):
    """Writes that fail mid-session (a stream that fills up: the full disk's ENOSPC from the same
    write): one line, the journal stops, the store records on, and what was journaled before still
    reads."""
    import arbiter_tui.session.journal as J

    disks: list[Filling] = []
    real = J._stream
    monkeypatch.setattr(J, "_stream", lambda fd: disks.append(Filling(real(fd))) or disks[-1])
    store = AnalyticsStore(10_000)
    store.start_collection()
    said: list[str] = []
    journal = Journal(Sources(store), tmp_path, 10**8, warn=said.append, flush_s=0.05)
    journal.start()
    for i in range(20):
        store.record(_point(i, None))
    wait_for(lambda: journal.written == 20, timeout=5)
    disks[0].full = True
    for i in range(20, 2000):
        store.record(_point(i, None))
    wait_for(lambda: said, timeout=5)
    journal.close()
    assert len(said) == 1 and said[0].startswith("journal stopped (No space left on device)"), said
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


def _free(lock) -> bool:
    """Whether another thread could take ``lock`` now."""
    got: list[bool] = []

    def take() -> None:
        ok = lock.acquire(blocking=False)
        got.append(ok)
        if ok:
            lock.release()

    thread = threading.Thread(target=take)
    thread.start()
    thread.join()
    return got[0]


def test_the_runs_summaries_are_computed_outside_the_stores_lock(tmp_path, monkeypatch):
    """The session records a sample under the store's lock while holding its own, and a stop needs the
    session's: a summary computed under the store's lock (2-8 ms for an hour's run) held up the stop."""
    from arbiter_tui.analytics import runs as runs_module

    store = AnalyticsStore(1000)
    store.start_collection()
    journal = Journal(Sources(store), tmp_path, 10**8, flush_s=3600)
    journal.start()
    wait_for(lambda: journal._channels is not None, timeout=5)
    run = store.begin_run("pure_pursuit", "square", 1.8e12)
    for i in range(50):
        store.record(_point(i, run))
    held: list[bool] = []
    compute = runs_module.compute_stats

    def spy(*args, **kwargs):
        held.append(not _free(store._lock))
        return compute(*args, **kwargs)

    monkeypatch.setattr(runs_module, "compute_stats", spy)
    with journal._lock:
        journal._step(force=True)
    journal.close()
    assert held and not any(held), held


def test_latency_is_not_kept_once_the_journal_stopped(tmp_path):
    store = AnalyticsStore(1000)
    journal = Journal(Sources(store), tmp_path, 10**8, flush_s=0.05)
    journal.start()
    wait_for(lambda: journal._channels is not None, timeout=5)
    journal.close()
    for k in range(100):
        journal.latency((float(k + 1),), (5.0,))
    assert len(journal._latency) == 0  # before: every record kept, for the rest of the session


def test_a_journal_that_fills_up_ends_its_file_and_an_error_ending_it_leaves_no_file_open(
    tmp_path, monkeypatch
):
    """The "full" branch: the file ends as ``full``, one line said; a failure while ending it (the disk)
    is one log line, the file closed, the thread ended (before: a traceback, the file left open)."""
    from arbiter_tui.analytics.exports import McapChannels

    store = AnalyticsStore(1000)
    store.start_collection()
    said: list[str] = []
    journal = Journal(Sources(store), tmp_path / "a", 1, warn=said.append, flush_s=0.05)
    journal.start()
    store.record(_point(0, None))
    wait_for(lambda: said, timeout=5)
    wait_for(lambda: journal._file is None, timeout=5)
    assert F.ending(journal.path) == F.FULL and said[0].startswith("journal full")

    def broken(self, *args, **kwargs):
        raise OSError(5, "Input/output error")

    monkeypatch.setattr(McapChannels, "finish", broken)
    errors: list[object] = []
    monkeypatch.setattr(threading, "excepthook", errors.append)
    said.clear()
    journal = Journal(Sources(store), tmp_path / "b", 1, warn=said.append, flush_s=0.05)
    journal.start()
    thread = journal._thread
    store.record(_point(1, None))
    wait_for(lambda: said and not thread.is_alive(), timeout=5)
    assert journal._file is None and errors == [] and said[0].startswith("journal full")
    journal.close()


def test_a_quit_while_the_journal_looks_back_opens_no_file_and_an_offer_is_counted_not_decoded(
    tmp_path, monkeypatch
):
    """close() gives up waiting for a thread still reading what the last session left; that thread must
    then open no new journal (before: a file nobody finished, offered at the next start as a 'killed'
    session of 0 samples). An offered journal's samples are counted from its summary, a cut one's by
    its chunks, without decoding it."""
    import arbiter_tui.session.journal as J

    store = AnalyticsStore(1000)
    store.start_collection()
    journal = Journal(Sources(store), tmp_path, 10**8, flush_s=0.05)
    journal.start()
    for i in range(30):
        store.record(_point(i, None))
    wait_for(lambda: journal.written == 30, timeout=5)
    journal.close("signal SIGHUP")  # a finished journal, to be offered
    first = journal.path

    looking = threading.Event()
    go_on = threading.Event()
    real = F.offerable

    def slow(directory, own=None):
        looking.set()
        go_on.wait(10)
        return real(directory, own)

    monkeypatch.setattr(F, "offerable", slow)
    monkeypatch.setattr(J, "CLOSE_WAIT_S", 0.05, raising=False)  # (before: a fixed 2 s)
    found: list[J.Found] = []
    journal = Journal(Sources(store), tmp_path, 10**8, found=found.append, flush_s=0.05)
    journal.start()
    thread = journal._thread
    looking.wait(5)
    journal.close()  # gives up on the thread
    go_on.set()
    thread.join(5)
    assert not thread.is_alive() and journal.path is None
    assert sorted(p.name for p in tmp_path.iterdir()) == [first.name.replace(".mcap", ".offered.mcap")]
    (offer,) = found
    assert offer.contents is not None and offer.contents.samples == 30
    assert "kept 30 samples" in offer.text()

    monkeypatch.setattr(J.F, "offerable", real)
    cut = tmp_path / "session_cut.mcap"
    data = first.with_name(first.name.replace(".mcap", ".offered.mcap")).read_bytes()
    cut.write_bytes(data[: len(data) // 2])
    got = F.contents(cut)
    assert got.samples is None and got.chunks >= 1 and "chunks" in got.words()


def test_a_close_never_waits_longer_than_its_bound_on_a_stalled_disk(tmp_path, monkeypatch):
    """The journal's thread stuck in an fsync (a stalled SD card) holds the writer's lock: a quit or a
    hang-up gives up on the file after CLOSE_WAIT_S (before: it waited on the lock for ever)."""
    import arbiter_tui.session.journal as J

    monkeypatch.setattr(J, "CLOSE_WAIT_S", 0.2, raising=False)  # (before: a fixed 2 s join, then for ever)
    store = AnalyticsStore(1000)
    journal = Journal(Sources(store), tmp_path, 10**8, flush_s=0.05)
    journal.start()
    wait_for(lambda: journal._channels is not None, timeout=5)
    stalled, done = threading.Event(), threading.Event()

    def fsync_forever() -> None:
        with journal._lock:
            stalled.set()
            done.wait(30)

    holder = threading.Thread(target=fsync_forever)
    holder.start()
    stalled.wait(5)
    closing = threading.Thread(target=journal.close)
    t0 = time.monotonic()
    closing.start()
    closing.join(10)
    took = time.monotonic() - t0
    done.set()
    holder.join(5)
    assert not closing.is_alive() and took < 5, took
