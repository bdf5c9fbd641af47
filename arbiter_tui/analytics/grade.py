"""A recording or an export on disk, graded: what ``arbiter-tui stats`` prints, for any caller (the CLI,
the analytics screen opening a file). One function, :func:`grade`: the file's runs and samples, each
run's and each controller's scorecard (``scorecards``), its ranking (``ranking``), what the file is and
what the figures cannot vouch for. Reads the file (``bags``, ``files``); the figures are the pure
modules'.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from . import scorecards as SC
from .bags import DEFAULT_CONFIG, DEFAULT_TOPICS, BagTopics, Recording, bag_kind, read_bag
from .exports import Export
from .files import load_export
from .model import DataPoint
from .observe import ObserveConfig
from .ranking import Entry, Ranking, rank
from .runs import RunSummary

NO_REFERENCE = "no reference: no goal or plan in the recording, so no error to measure"


@dataclass(frozen=True, slots=True)
class Graded:
    path: Path
    what: str  # "ros2 bag directory (MCAP, 1 file)", "arbiter analytics export"
    export: Export
    cards: tuple[SC.RunCard, ...]  # one per run, in run order
    controllers: tuple[SC.ControllerCard, ...]  # one per algorithm, in first-run order
    notes: tuple[str, ...]  # what the figures cannot vouch for, each once
    is_bag: bool

    @property
    def runs(self) -> tuple[RunSummary, ...]:
        """The runs in the order ``stats --by run`` prints them (run order)."""
        return tuple(sorted(self.export.runs or (), key=lambda r: r.id))

    def ranking(self) -> Ranking:
        """As the analytics screen ranks its rows: per mission, then overall (``ranking``)."""
        rows: Sequence[Entry] = self.export.algorithms or self.runs
        return rank(rows)

    @property
    def no_reference(self) -> str:
        """Why the file's error stats have no reference ("" where they have one): a recording in which
        no goal or plan came (no run) has no error to measure; its samples' errors, 0, are no figure."""
        return NO_REFERENCE if self.is_bag and not self.export.runs else ""

    def card(self, run_id: int) -> SC.RunCard | None:
        return next((c for c in self.cards if c.run == run_id), None)


def grade(path: Path, topics: BagTopics = DEFAULT_TOPICS, config: ObserveConfig = DEFAULT_CONFIG) -> Graded:
    """The file at ``path`` (a ros2 bag, or a CSV, JSON or MCAP export) graded. Raises
    ``ExportFormatError`` (``bags.OutOfMemory`` when memory ran out) with one line saying what is wrong,
    ``OSError`` (``FileNotFoundError``, ``PermissionError``) when it cannot be read."""
    path = Path(path)
    notes: list[str] = []
    recording: Recording | None
    if bag_kind(path) is not None:
        recording = read_bag(path, topics, config, warn=notes.append)
        export, what = recording.export, recording.what
        no_scan = f"no sensor_msgs/LaserScan on {topics.scan} in the recording"
        scans = recording.scans
    else:
        export = load_export(path)
        notes.extend(export.notes)
        recording, what, scans = None, "arbiter analytics export", None
        no_scan = "an export holds no scans: grade the ros2 bag with its /scan"
    by_run: dict[int | None, list[DataPoint]] = {}
    for p in export.points:  # once, not once per run
        by_run.setdefault(p.runId, []).append(p)
    runs = sorted(export.runs or (), key=lambda r: r.id)
    cards = tuple(_card(r, by_run.get(r.id, []), scans, no_scan) for r in runs)
    return Graded(
        path, what, export, cards, tuple(SC.controller_cards(cards)), tuple(notes), recording is not None
    )


def _card(run: RunSummary, mine: list[DataPoint], scans: SC.Scans | None, no_scan: str) -> SC.RunCard:
    """``mine``: the run's points, in the export's order."""
    samples = None
    if mine and len(mine) == run.stats.sampleCount:
        samples = (
            np.array([p.timestamp for p in mine]),
            np.array([p.x for p in mine]),
            np.array([p.y for p in mine]),
        )
    if scans is None:
        obstacles = SC.no_obstacles(no_scan)
    else:
        end = run.end_ms if run.end_ms is not None else (run.last_ms or run.start_ms)
        obstacles = SC.obstacles_of(scans.between(run.start_ms, end))
    return SC.run_card(run, samples, obstacles)
