"""The user-space impaired link moved to ``tests/support/tunlink.py`` (the tests use it too); bench
scripts that ``from tunlink import TunLink`` (bench/ on the path) get it from there."""

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from tests.support.tunlink import Impairment, TunLink

__all__ = ["Impairment", "TunLink"]
