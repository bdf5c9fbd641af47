"""Each screen update (Textual's compositor render) and each frame sampled, as the console does them:
put this folder on PYTHONPATH and a process that imports Textual's screen writes one line per update to
/tmp/arbiter-render-PID.log: ``render <epoch s> <wall ms> <cpu ms>``, and one per ``sample_frame``:
``sample ...`` the same way. Epoch time, so that bench/render_overlap.py can set them beside the
tracker's records of the same run:

    sudo python bench/pi.py --size 200x60 --no-key-to-wire --screens control,analytics \\
        --pythonpath "$PWD:$PWD/bench/renderprobe" --records recs.jsonl
    python bench/render_overlap.py recs.jsonl /tmp/arbiter-render-*.log

It wraps two methods (one ``time.time`` and one ``time.thread_time`` pair each, a line written after):
small beside a render of several milliseconds.
"""

import importlib.abc
import importlib.machinery
import os
import sys
import time

_log = None


def _write(kind: str, t0: float, c0: float) -> None:
    global _log
    if _log is None:
        _log = open(f"/tmp/arbiter-render-{os.getpid()}.log", "a", buffering=1)  # noqa: SIM115
    _log.write(f"{kind} {t0:.6f} {(time.time() - t0) * 1000:.3f} {(time.thread_time() - c0) * 1000:.3f}\n")


def _timed(kind: str, method):
    def timed(self, *args, **kwargs):
        t0, c0 = time.time(), time.thread_time()
        try:
            return method(self, *args, **kwargs)
        finally:
            _write(kind, t0, c0)

    return timed


def _screen(module) -> None:
    module.Screen._on_timer_update = _timed("render", module.Screen._on_timer_update)


def _app(module) -> None:
    module.ArbiterApp.sample_frame = _timed("sample", module.ArbiterApp.sample_frame)


_HOOKS = {"textual.screen": _screen, "arbiter_tui.shell.app": _app}


class _AfterImport(importlib.abc.MetaPathFinder):
    """Finds the modules of ``_HOOKS`` with the other finders and patches each once it has run."""

    def find_spec(self, name, path, target=None):
        hook = _HOOKS.get(name)
        if hook is None:
            return None
        for finder in sys.meta_path:
            if finder is not self and hasattr(finder, "find_spec"):
                spec = finder.find_spec(name, path, target)
                if spec is not None and isinstance(spec.loader, importlib.machinery.SourceFileLoader):
                    run = spec.loader.exec_module

                    def exec_module(module, run=run, hook=hook):
                        run(module)
                        hook(module)

                    spec.loader.exec_module = exec_module
                    return spec
        return None


sys.meta_path.insert(0, _AfterImport())
