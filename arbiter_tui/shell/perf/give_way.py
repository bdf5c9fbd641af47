"""A paint gives way to the robot's next control tick, where the console has no core to spare.

The widgets that cost most to paint (every ``Bound`` text widget, every plot canvas) call :func:`now`
before they paint; once the app has :func:`install`-ed its session's ``give_way``, a paint that would
run over the next control tick stops short of it until the tick's command is written
(``RobotSession.give_way``). Installed only for a live session on a console with less than
``SPARE_CORES`` cores (``session/cpu_share.py``): with a core to spare the threads do not wait for
each other's CPU time, only for the GIL, and a paint there is short.
"""

from __future__ import annotations

from collections.abc import Callable

GUARD_S = 0.01  # a tick due within this long (a scheduling period of the Pi stand-in's quota) waits

_hook: Callable[[], object] | None = None


def install(hook: Callable[[], object] | None) -> None:
    """``hook`` is asked before each widget's paint (None: nothing is)."""
    global _hook
    _hook = hook


def now() -> None:
    if _hook is not None:
        _hook()
