"""Old import paths, kept for code written against an earlier copi.

A module that moved leaves a shim of a few lines that warns (``DeprecationWarning``) when
it is imported and hands every name on to the module's new home (:func:`forward`); a
package whose names moved elsewhere hands each of them on, warning when one is used
(:func:`moved_names`)."""

from __future__ import annotations

import importlib
import warnings
from collections.abc import Callable, Mapping
from typing import Any

__all__ = ["forward", "moved_names"]


def _warn(old: str, new: str) -> None:
    warnings.warn(
        f"{old} moved to {new}: import it from there (the old path will be removed)",
        DeprecationWarning,
        stacklevel=3,
    )


def forward(
    old: str, *new: str, renamed: Mapping[str, str] | None = None
) -> Callable[[str], Any]:
    """Warn that module ``old`` moved to ``new`` (one module or several, searched in
    order), and return the ``__getattr__`` that makes ``old``'s names theirs
    (``renamed``: old name -> new name)."""
    _warn(old, " and ".join(new))
    modules = [importlib.import_module(m) for m in new]
    names = dict(renamed or {})

    def __getattr__(name: str) -> Any:
        target = names.get(name, name)
        for module in modules:
            if hasattr(module, target):
                return getattr(module, target)
        raise AttributeError(f"module {old!r} (now {', '.join(new)}) has no attribute {name!r}")

    return __getattr__


def moved_names(package: str, moved: Mapping[str, str]) -> Callable[[str], Any]:
    """The ``__getattr__`` of a package some of whose names moved: ``moved`` maps each to
    ``"new.module"`` or ``"new.module:new_name"``; using one warns once per use."""

    def __getattr__(name: str) -> Any:
        if name not in moved:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        where, _, new = moved[name].partition(":")
        _warn(f"{package}.{name}", f"{where}.{new or name}")
        return getattr(importlib.import_module(where), new or name)

    return __getattr__
