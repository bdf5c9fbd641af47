"""Command line of ``arbiter-tui``."""

from __future__ import annotations

import os
import sys
from collections.abc import Callable


def _command(name: str) -> Callable[[list[str]], int] | None:
    """The subcommand called ``name`` (imported only when asked for), or None."""
    if name == "stats":
        from .commands.stats import run

        return run
    if name == "compare":
        from .commands.compare import run as run_compare

        return run_compare
    if name == "autonomy":
        from .commands.autonomy import run as run_autonomy

        return run_autonomy
    if name == "topics":
        from .commands.topics import run as run_topics

        return run_topics
    if name == "fleet":
        from .fleet.command import run as run_fleet

        return run_fleet
    return None


def main(argv: list[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    try:
        try:
            command = _command(argv[0]) if argv else None
            if command is not None:
                return command(argv[1:])
            from .launch import run_app

            return run_app(argv)
        finally:
            sys.stdout.flush()  # here, not at exit: a reader that left is then caught below
    except BrokenPipeError:
        # The reader left early (`| head`, `| grep -q`): stop quietly, as command-line tools do. stdout
        # goes to devnull so the interpreter's own flush at exit does not fail again (the Python docs'
        # recipe, "Note on SIGPIPE").
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 1


if __name__ == "__main__":
    sys.exit(main())
