"""numba's on-disk cache of copi's kernels, kept fresh against every kernel's source.

numba keys a cached kernel by its own file alone, yet a call between compiled functions is
compiled into the caller: a kernel whose callee lives in another file (the learnt
decision calls the safety network of :mod:`copi.learning.kernels`, the crowd's scan the
geometry's ray tests) would keep running the callee it was compiled with after that file
changed, until its own file changes too. Here each of copi's cached kernels is stamped
instead with a hash of every copi source file that holds kernels, so that editing any of
them recompiles them all on their next use (nothing else: a file without kernels does not
count). Installed on import, which ``import copi`` does before any kernel is defined;
with a numba whose cache internals differ (they are not public API), numba's own per-file
stamps are kept.
"""

from __future__ import annotations

import hashlib
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parent
"""The package whose kernels are stamped together."""

_stamps: dict[Path, str] = {}


def kernels_stamp(root: Path = ROOT) -> str:
    """A hash of every ``.py`` file under ``root`` that defines numba kernels (its path
    and bytes, in sorted order), computed once a process."""
    if root not in _stamps:
        h = hashlib.sha256()
        for path in sorted(root.rglob("*.py")):
            data = path.read_bytes()
            if b"njit" in data:
                h.update(path.relative_to(root).as_posix().encode() + b"\0" + data + b"\0")
        _stamps[root] = h.hexdigest()
    return _stamps[root]


def _stamped(base: Any) -> Any:
    """numba's cache locator ``base`` for copi's files only, stamped by
    :func:`kernels_stamp`."""

    class Stamped(base):  # type: ignore[misc, valid-type]
        def get_source_stamp(self) -> str:
            return kernels_stamp()

        @classmethod
        def from_function(cls, py_func: Any, py_file: str) -> Any:
            try:
                if not Path(py_file).resolve().is_relative_to(ROOT):
                    return None
            except OSError:
                return None
            return super().from_function(py_func, py_file)

    Stamped.__name__ = Stamped.__qualname__ = f"Copi{base.__name__}"
    return Stamped


def install() -> None:
    """Put the stamped locators first in numba's list (a user's ``NUMBA_CACHE_DIR`` still
    first among them, as numba orders its own); once."""
    try:
        from numba.core import caching

        def named(name: str) -> Any:  # numba before 0.60 kept a leading underscore
            return getattr(caching, name, None) or getattr(caching, f"_{name}")

        classes = named("CacheImpl")._locator_classes
        bases = (named("UserProvidedCacheLocator"), named("InTreeCacheLocator"))
    except (ImportError, AttributeError):  # pragma: no cover - another numba's internals
        return
    if any(c.__name__.startswith("Copi") for c in classes):
        return
    classes[:0] = [_stamped(b) for b in bases]


install()
