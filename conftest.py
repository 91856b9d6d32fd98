"""Collection of the doctests in src/copi: the shims that keep old import paths working
warn when they are imported (warnings are errors in the tests), so they are not collected
as modules; tests/test_public_api.py checks each of them."""

from __future__ import annotations

from pathlib import Path

_SRC = Path(__file__).parent / "src" / "copi"

collect_ignore = [
    str(p) for p in _SRC.rglob("*.py") if "from copi._moved import forward" in p.read_text()
]
