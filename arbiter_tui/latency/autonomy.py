"""The robot-side controller's API answers (``arbiter-backend --autonomy``: ``/api/autonomy``) as
values: what the console shows of it and what a stop learns from it. Pure: the client that asks is
``autonomy_client.py``."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any


class AutonomyUnavailable(Exception):
    """The API could not be asked, or refused: one line (``disabled`` when the backend runs without
    ``--autonomy``, its 403)."""

    def __init__(self, text: str, disabled: bool = False, status: int | None = None) -> None:
        super().__init__(text)
        self.disabled = disabled
        self.status = status


@dataclass(frozen=True, slots=True)
class AutonomyStatus:
    """The API's answer (``GET``/``POST``/``DELETE /api/autonomy``)."""

    state: str  # idle, running, completed, aborted
    algorithm: str | None = None
    mission: str | None = None
    waypoint: int | None = None
    waypoints: int | None = None
    commands: int = 0
    final_error_m: float | None = None
    stopped: bool = False  # DELETE only: this request stopped a run

    @classmethod
    def of(cls, body: Any) -> AutonomyStatus:
        if not isinstance(body, dict) or not isinstance(body.get("state"), str):
            raise ValueError("not an autonomy status: no state")

        def opt(name: str, kind: type | tuple[type, ...]) -> Any:
            value = body.get(name)
            return value if isinstance(value, kind) and not isinstance(value, bool) else None

        return cls(
            state=body["state"],
            algorithm=opt("algorithm", str),
            mission=opt("mission", str),
            waypoint=opt("waypoint", int),
            waypoints=opt("waypoints", int),
            commands=opt("commands", int) or 0,
            final_error_m=opt("final_error_m", (int, float)),
            stopped=body.get("stopped") is True,
        )

    @property
    def running(self) -> bool:
        return self.state == "running"

    def run(self) -> str:
        """``stanley on corner at 1/2``"""
        if self.algorithm is None:
            return self.state
        return f"{self.algorithm} on {self.mission} at {self.waypoint}/{self.waypoints}"

    def line(self) -> str:
        """One line, as ``arbiter-tui autonomy`` prints it."""
        if self.algorithm is None:
            return f"autonomy: {self.state}"
        final = "" if self.final_error_m is None else f", final error {self.final_error_m:.3f} m"
        return (f"autonomy: {self.state} · {self.algorithm} on {self.mission} · waypoint {self.waypoint}/"
                f"{self.waypoints} · {self.commands} commands{final}")  # fmt: skip


@dataclass(frozen=True, slots=True)
class RobotSideView:
    """The backend's robot-side controller (``arbiter-backend --autonomy``), as its API last answered."""

    known: bool = False  # asked and answered (or refused)
    enabled: bool = False  # the backend runs it (not 403)
    running: bool = False
    text: str = "not asked yet"  # its state ("running", "idle"), or why it cannot be asked
    run: str = ""  # the run in progress or the last one: "stanley on corner at 1/2"
    algorithm: str = ""  # its controller ("" before any run)

    @property
    def driving(self) -> str | None:
        """What drives the robot, for the status line: ``robot-side stanley`` while it runs."""
        return f"robot-side {self.algorithm}" if self.running and self.algorithm else None
