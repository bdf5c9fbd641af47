"""``arbiter-tui fleet``: many robots in one console, over Zenoh (docs/fleet.md).

``rows`` is the pure model (one row per robot ever seen: alive, stale or lost, never dropped; bad data
marked; severity order; the cells both the screen and ``--json`` show), ``client`` the Zenoh session
that feeds it, ``app`` the Textual screen, ``command`` the command line. Only ``client`` imports Zenoh;
nothing on the single-robot console's path imports this package (import-linter contracts).
"""
