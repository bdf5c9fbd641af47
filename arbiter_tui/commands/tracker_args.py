"""The backend-API arguments the headless subcommands share (``--tracker``, ``--token-file``,
``--ca-file``, ``--timeout``), and their checking, in one place."""

from __future__ import annotations

import argparse
from dataclasses import dataclass
from pathlib import Path

from arbiter_core.auth import load_token
from arbiter_core.urls import Endpoint, UrlError, check_token_transport, tracker_endpoint

DEFAULT_TRACKER = "http://127.0.0.1:8085"


def add(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--tracker", default=DEFAULT_TRACKER, help=f"the backend's API (default {DEFAULT_TRACKER})"
    )
    p.add_argument(
        "--token-file", type=Path, help="file whose first line is the token (default $ARBITER_TOKEN)"
    )
    p.add_argument("--ca-file", type=Path, help="PEM certificate(s) to trust for https://")
    p.add_argument("--timeout", type=float, default=5.0, help="seconds to wait for an answer (default 5)")


@dataclass(frozen=True)
class Tracker:
    endpoint: Endpoint
    token: str | None


def checked(args: argparse.Namespace) -> Tracker:
    """The endpoint and token the arguments name; ValueError, AuthConfigError or UrlError in one line."""
    endpoint = tracker_endpoint(args.tracker)
    token = load_token(args.token_file)
    check_token_transport(endpoint, "--tracker", token)
    if args.ca_file is not None and not args.ca_file.is_file():
        raise UrlError(f"--ca-file {args.ca_file}: no such file")
    return Tracker(endpoint, token)
