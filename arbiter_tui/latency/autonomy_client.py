"""The robot-side controller's API (``arbiter-backend --autonomy``: ``/api/autonomy`` on the tracker's
HTTP server), asked synchronously: from the stop's own thread (``session/remote_stop.py``), from a
worker thread of the console (start, status), and by ``arbiter-tui autonomy``. One definition of the
calls and of what an answer means."""

from __future__ import annotations

import ssl
from pathlib import Path
from typing import Any

from arbiter_core.failures import connect_failure

from .autonomy import AutonomyStatus, AutonomyUnavailable

TIMEOUT_S = 2.0


class AutonomyClient:
    """``/api/autonomy`` of one backend, with the tracker's token and TLS settings."""

    def __init__(
        self,
        base_url: str,
        token: str | None = None,
        ca_file: Path | None = None,
        timeout: float = TIMEOUT_S,
    ) -> None:
        self.url = f"{base_url.rstrip('/')}/api/autonomy"
        self._headers = {} if token is None else {"Authorization": f"Bearer {token}"}
        # https:// verified against the system's CAs, or against --ca-file (a private CA)
        self._verify: Any = True if ca_file is None else ssl.create_default_context(cafile=str(ca_file))
        self._timeout = timeout

    def request(self, method: str, body: dict[str, Any] | None = None) -> dict[str, Any]:
        """The API's JSON answer; :class:`AutonomyUnavailable` when it cannot be asked or refuses."""
        import httpx

        try:
            resp = httpx.request(
                method, self.url, json=body, headers=self._headers, timeout=self._timeout, verify=self._verify
            )
            answer = resp.json()
        except httpx.TimeoutException:
            raise AutonomyUnavailable(f"{self.url}: timed out") from None
        except httpx.HTTPError as exc:
            raise AutonomyUnavailable(connect_failure(type(exc).__name__, str(exc))) from None
        except ValueError:
            raise AutonomyUnavailable(f"{self.url}: {resp.status_code} {resp.text[:200]}") from None
        if resp.status_code >= 400 or not isinstance(answer, dict):
            why = answer.get("error") if isinstance(answer, dict) else None
            raise AutonomyUnavailable(
                f"{resp.status_code} {why or resp.text[:200]}", disabled=resp.status_code == 403,
                status=resp.status_code,
            )  # fmt: skip
        return answer

    def status(self) -> AutonomyStatus:
        return self._status("GET")

    def stop(self) -> AutonomyStatus:
        return self._status("DELETE")

    def start(self, algorithm: str, mission: str, speed: float, turn: float) -> AutonomyStatus:
        body = {"algorithm": algorithm, "mission": mission, "speed": speed, "turn": turn}
        return self._status("POST", body)

    def _status(self, method: str, body: dict[str, Any] | None = None) -> AutonomyStatus:
        answer = self.request(method, body)
        try:
            return AutonomyStatus.of(answer)
        except ValueError as exc:
            raise AutonomyUnavailable(f"{self.url}: {exc}") from None
