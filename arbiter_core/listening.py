"""The backend's one-line "listening" announcement: written by ``arbiter-backend`` on stdout once its
sockets are bound, read by whoever started it (the console's embedded mode, benches, tests).

One definition of the line on both sides, so the format cannot drift between writer and readers.
"""

from __future__ import annotations

from dataclasses import dataclass

PREFIX = "arbiter-backend listening: "


@dataclass(frozen=True, slots=True)
class Listening:
    host: str
    bridge_port: int | None  # None: started with --no-bridge
    api_port: int
    secure: bool = False  # wss:// and https://
    extras: tuple[tuple[str, str], ...] = ()  # deploy_mode, sim, transport, auth, in the order written

    def extra(self, key: str) -> str | None:
        return dict(self.extras).get(key)


def format_listening(
    host: str, bridge_port: int | None, api_port: int, secure: bool = False, **extras: str
) -> str:
    parts = []
    if bridge_port is not None:
        parts.append(f"rosbridge={'wss' if secure else 'ws'}://{host}:{bridge_port}")
    parts.append(f"api={'https' if secure else 'http'}://{host}:{api_port}")
    parts.extend(f"{key}={value}" for key, value in extras.items())
    return PREFIX + " ".join(parts)


def parse_listening(line: str) -> Listening | None:
    """The announcement in ``line`` (anywhere in it), or None when the line is something else."""
    _, found, rest = line.partition(PREFIX)
    if not found:
        return None
    fields: dict[str, str] = {}
    for part in rest.split():
        key, eq, value = part.partition("=")
        if eq:
            fields[key] = value
    try:
        api = fields.pop("api")
        secure = api.startswith("https://")
        host, api_port = _host_port(api, "https://" if secure else "http://")
        bridge = fields.pop("rosbridge", None)
        bridge_port = None if bridge is None else _host_port(bridge, "wss://" if secure else "ws://")[1]
    except (KeyError, ValueError):
        return None
    return Listening(host, bridge_port, api_port, secure, tuple(fields.items()))


def _host_port(url: str, scheme: str) -> tuple[str, int]:
    if not url.startswith(scheme):
        raise ValueError(url)
    host, _, port = url[len(scheme) :].rpartition(":")
    if not host:
        raise ValueError(url)
    return host, int(port)
