"""Latency screen: the tracker's stats, a sparkline of the rolling window, recent records."""

from __future__ import annotations

from rich.text import Text
from textual.app import ComposeResult
from textual.widgets import DataTable, Sparkline, Static

from .base import BaseScreen

CARDS = (("count", "count"), ("mean_ms", "mean"), ("min_ms", "min"), ("max_ms", "max"), ("p95_ms", "p95"),
         ("stddev_ms", "stddev"))  # fmt: skip


def fmt_ms(value: object) -> str:
    if value is None:
        return "N/A"
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        return f"{value:.3f} ms"
    return "?"


def fmt_signed(value: float | None) -> str:
    return "N/A" if value is None else f"{value:+.3f} ms"


class LatencyScreen(BaseScreen):
    DEFAULT_CSS = """
    LatencyScreen #lat-cards { height: 3; padding: 0 1; }
    LatencyScreen #lat-client { height: 3; padding: 0 1; }
    LatencyScreen #lat-state { height: 1; padding: 0 1; }
    LatencyScreen #lat-spark { height: 5; border: round $primary; }
    LatencyScreen #lat-records { height: 1fr; }
    """

    _drawn_key: object = None

    def compose_body(self) -> ComposeResult:
        yield Static(id="lat-state")
        yield Static(id="lat-cards")
        yield Static(id="lat-client")
        yield Sparkline([], id="lat-spark")
        yield DataTable(id="lat-records", show_cursor=False, zebra_stripes=True)

    def on_mount(self) -> None:
        self.query_one("#lat-records", DataTable).add_columns(
            "seq", "latency", "linear_x", "angular_z", "mode"
        )
        super().on_mount()

    def refresh_view(self) -> None:
        if not self.ready:
            return
        super().refresh_view()
        app = self.arbiter
        view = app.latency_view()
        state = Text()
        if view is None:
            state.append("Client-side simulation: no network path, latency N/A", "bold")
        elif view.reachable is None:
            state.append("Polling the tracker…", "bold")
        elif not view.reachable:
            state.append(f"TRACKER UNREACHABLE ({view.error}) — retrying every 0.5 s", "bold red")
        else:
            state.append("tracker reachable", "bold green")
            state.append(f" · deploy mode {view.deploy_mode} · {len(view.window)} samples in window")
            if view.stale:  # the robot ignores these: the operator must know why it does not move
                limit = "" if view.max_command_age_ms is None else f" > {view.max_command_age_ms:g} ms"
                state.append(f" · {view.stale} STALE{limit}, not forwarded", "bold red")
            if view.rejected:
                state.append(f" · {view.rejected} rejected", "bold yellow")
        self.query_one("#lat-state", Static).update(state)
        stats = view.stats if view is not None else {}
        cards = Text()
        for i, (key, label) in enumerate(CARDS):
            value = stats.get(key)
            text = str(value) if key == "count" and value is not None else fmt_ms(value)
            if key == "count" and value is None:
                text = "N/A"
            cards.append(f"{label:>7} ", "bold")
            cards.append(f"{text:<14}")
            if i == 2:
                cards.append("\n")
        self.query_one("#lat-cards", Static).update(cards)
        client = self.query_one("#lat-client", Static)
        client.display = view is not None
        client.update(self._client_side(view is None))
        # the sparkline and table change only when a poll brought something: redrawing them at the
        # UI rate regardless cost ~4x the CPU and terminal output of the whole screen (bench/tui.py)
        key = None if view is None else (view.failures, view.version)
        if key == self._drawn_key and key is not None:
            return
        self._drawn_key = key
        self.query_one("#lat-spark", Sparkline).data = list(view.window) if view is not None else []
        table = self.query_one("#lat-records", DataTable)
        table.clear()
        if view is not None:
            for r in list(reversed(view.records))[:30]:
                table.add_row(
                    "" if r.seq is None else str(r.seq),
                    fmt_ms(r.latency_ms),
                    f"{r.linear_x:+.2f}",
                    f"{r.angular_z:+.2f}",
                    r.deploy_mode,
                )

    def _client_side(self, simulated: bool) -> Text:
        """This console's own view: round trip, offset (NTP method), corrected one-way, loss."""
        out = Text()
        if simulated:
            return out
        s = self.arbiter.link.telemetry.meter.summary()
        out.append("this console", "bold")
        if self.arbiter.link_down():
            out.append(
                f" · ROSBRIDGE LINK {self.arbiter.link.state}: no commands, no round trips"
                f" · sent {s['sent']} · lost {s['lost']}",
                "bold red",
            )
            return out
        if not s["n"]:
            out.append(f" · no round trips yet · sent {s['sent']} · lost {s['lost']}")
            return out
        out.append(f" · rtt p50 {fmt_ms(s['rtt_p50_ms'])} p95 {fmt_ms(s['rtt_p95_ms'])}")
        out.append(
            f" · one-way corrected p50 {fmt_ms(s['corrected_p50_ms'])} (raw {fmt_ms(s['raw_p50_ms'])})\n"
        )
        off, unc = s["offset_ms"], s["offset_uncertainty_ms"]
        out.append(f"clock offset {fmt_signed(off)} ± {fmt_ms(unc)}")
        out.append(f" · negative {s['negative']} · lost {s['lost_in_window']} in 10 s ({s['lost']} total)")
        warn = self.arbiter.settings.offset_warn_ms
        if off is not None and abs(off) > warn:
            out.append(
                f"\nCLOCK OFFSET {off:+.1f} ms exceeds {warn:g} ms: raw one-way figures include it",
                "bold red",
            )
        return out
