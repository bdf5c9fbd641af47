"""A recording or an export opened on the analytics screen: its runs ranked and plotted exactly as
``arbiter-tui stats`` grades them (``analytics.grade``, one function for both), as the screen's
:class:`~.views.AnalyticsView`, marked with what the file is. No Textual.

The cards are the file's nine stats over all its samples (what ``stats FILE`` prints); the runs and
the per-(mission, algorithm) rows are the file's own (a bag's graded runs; an export's summaries as the
console recorded them over all of their samples). A CSV export carries neither outcomes nor missions:
its runs are rebuilt from its ``runId`` column, each "ended", so nothing is ranked. The plots draw every
sample of the file, thinned as the live ones are.
"""

from __future__ import annotations

import time
from dataclasses import replace
from pathlib import Path

from ..analytics.grade import Graded, grade
from ..analytics.model import stats_of_points
from ..analytics.runs import ENDED
from ..analytics.store import MAX_CAPACITY, AnalyticsStore
from .views import AnalyticsView, analytics_view

NO_OUTCOMES = "a CSV export carries no run outcomes or missions: its runs are shown, none is ranked"


def open_recording(path: Path) -> AnalyticsView:
    """Read and grade ``path`` (blocking: a worker's thread). ``ExportFormatError`` (one line) or
    ``OSError`` when it cannot be read."""
    return recording_view(grade(Path(path)))


def recording_view(graded: Graded, now: float | None = None) -> AnalyticsView:
    export = graded.export
    points = export.points
    store = AnalyticsStore(max_data_points=max(1, min(len(points), MAX_CAPACITY)))
    store.start_collection()
    notes = list(graded.notes)
    if graded.no_reference:
        notes.append(graded.no_reference)  # beside the cards' "—"
    if export.runs is None:  # a CSV: runs rebuilt from its runId column, in file order
        notes.append(NO_OUTCOMES)
        current = None
        for p in points:
            if p.runId != current:
                if current is not None:
                    store.end_run(ENDED, p.timestamp)
                if p.runId is not None:
                    store.begin_run(p.algorithm, "", p.timestamp)
                current = p.runId
            store.record(replace(p, runId=store.active_run if p.runId is not None else None))
        if current is not None:
            store.end_run(ENDED, points[-1].timestamp)
    else:
        for p in points:
            store.record(replace(p, runId=None))  # the plots' samples; the runs are the file's own
    store.stop_collection()
    view = analytics_view(store, None, None, time.monotonic() if now is None else now)
    runs = store.runs() if export.runs is None else graded.runs
    algorithms = store.runs_by_algorithm() if export.algorithms is None else export.algorithms
    name = graded.path.name or str(graded.path)
    return replace(
        view,
        stats=stats_of_points(points),
        runs=runs,
        by_algorithm=algorithms,
        ring=len(points),
        source=f"{name} ({graded.what})",
        notes=tuple(notes),
        plans=len(export.plans),
        no_reference=graded.no_reference,
    )
