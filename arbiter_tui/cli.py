"""Command line of ``arbiter-tui``."""

from __future__ import annotations

import sys


def main(argv: list[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    if argv and argv[0] == "stats":
        from .commands.stats import run

        return run(argv[1:])
    if argv and argv[0] == "compare":
        from .commands.compare import run as run_compare

        return run_compare(argv[1:])
    if argv and argv[0] == "autonomy":
        from .commands.autonomy import run as run_autonomy

        return run_autonomy(argv[1:])
    if argv and argv[0] == "topics":
        from .commands.topics import run as run_topics

        return run_topics(argv[1:])
    from .launch import run_app

    return run_app(argv)


if __name__ == "__main__":
    sys.exit(main())
