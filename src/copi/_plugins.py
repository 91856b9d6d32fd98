"""Third-party extensions through entry points (as Gymnasium loads environments and
navground behaviours): each entry point of a group names a callable taking no argument
that registers what its package adds when called."""

from __future__ import annotations

import functools
import hashlib
import importlib.metadata
import inspect
import re
import sys
import threading
import warnings
from pathlib import Path
from typing import Any, Generic, TypeVar

from copi.errors import CopiError, InvalidArgumentError, PluginWarning

__all__ = [
    "Registry",
    "failed_entry_points",
    "load_entry_points",
    "origin_of",
    "replaced_origin",
]

_LOADED: set[tuple[str, str, str]] = set()
_FAILED: dict[str, list[str]] = {}
_LOCK = threading.RLock()


def load_entry_points(group: str) -> int:
    """Call every entry point of ``group`` not called yet in this process (a package
    installed, or put on the path, since the last call is picked up); returns how many
    were called. An entry point that cannot be loaded, or whose call fails, is skipped
    with one :class:`~copi.errors.PluginWarning` naming it (one broken package does not
    stop the others, nor copi's own); :func:`failed_entry_points` keeps what it said, so
    that a name only it could have registered is refused saying why."""
    called = 0
    with _LOCK:
        for ep in importlib.metadata.entry_points(group=group):
            key = (group, ep.name, ep.value)
            if key in _LOADED:
                continue
            _LOADED.add(key)  # once, even if it fails: the warning says so
            try:
                hook = ep.load()
                if callable(hook):
                    hook()
            except CopiError as exc:
                _skip(group, f"entry point {ep.name!r} ({ep.value}) of {group}: {exc}")
                continue
            except Exception as exc:
                _skip(group, f"entry point {ep.name!r} ({ep.value}) of {group} cannot be "
                             f"loaded ({type(exc).__name__}: {exc})")  # fmt: skip
                continue
            called += 1
    return called


def _skip(group: str, message: str) -> None:
    _FAILED.setdefault(group, []).append(message)
    warnings.warn(f"{message}; skipped", PluginWarning, stacklevel=3)


def failed_entry_points(group: str) -> tuple[str, ...]:
    """What each entry point of ``group`` that could not be loaded said, in order."""
    with _LOCK:
        return tuple(_FAILED.get(group, ()))


@functools.lru_cache(maxsize=1)
def _distributions() -> dict[str, list[str]]:
    return dict(importlib.metadata.packages_distributions())


def _defining_module(thing: Any) -> str:
    """The module that defines ``thing``: its ``__module__``, unless that is the standard
    library's (a class made with ``type()`` under an ABC says ``abc``), in which case the
    module of the first function it defines itself."""
    module_name = getattr(thing, "__module__", None) or type(thing).__module__
    top = module_name.split(".")[0]
    if top in sys.stdlib_module_names or top == "builtins":
        for value in vars(thing).values() if isinstance(thing, type) else ():
            func = getattr(value, "__func__", value)
            mod = getattr(func, "__module__", None)
            std = mod is None or mod.split(".")[0] in sys.stdlib_module_names
            if inspect.isfunction(func) and not std:
                return str(mod)
    return str(module_name)


def _source_files(module_name: str) -> list[Path]:
    """The source files a module's results may depend on: every ``.py`` file of its
    top-level package, or for a module of its own, it and the modules loaded from its
    directory (a helper it imports), unless that directory is an installation's shared
    one (site-packages), where only the module itself is its own."""
    top = module_name.split(".")[0]
    root = sys.modules.get(top)
    where = getattr(root, "__path__", None)
    if where:  # a package: all of it
        return sorted(p for d in where for p in Path(d).rglob("*.py"))
    file = getattr(sys.modules.get(module_name), "__file__", None)
    if not file:
        return []
    here = Path(file).resolve()
    if any(part in ("site-packages", "dist-packages") for part in here.parts):
        return [here]
    mine = {here}
    for mod in list(sys.modules.values()):
        f = getattr(mod, "__file__", None)
        if f and f.endswith(".py") and Path(f).resolve().parent == here.parent:
            mine.add(Path(f).resolve())
    return sorted(mine)


def origin_of(thing: Any, kind: str) -> dict[str, str]:
    """Where a registered method's factory or a family's sampler comes from, for the
    identity of every run of it (``kind``: "method" or "family" names the keys): nothing
    for copi's own (copi's version is in every identity already); otherwise its package
    and version (``KIND_origin``) and a hash of the source of every module of its package
    (``KIND_code``: for a module of its own, it and the modules beside it), so that a run
    of another package's thing of the same name, or of its code changed since (in any
    of its modules), never resumes into the stored one.

    Examples
    --------
    >>> from copi.baselines import DWA
    >>> origin_of(DWA, "method")
    {}
    """
    module_name = _defining_module(thing)
    if module_name == "copi" or module_name.startswith("copi."):
        return {}
    top = module_name.split(".")[0]
    dists = _distributions().get(top, [])
    if not dists:  # a package installed (or put on the path) since the first look
        _distributions.cache_clear()
        dists = _distributions().get(top, [])
    package = module_name
    if dists:
        try:
            package = f"{dists[0]} {importlib.metadata.version(dists[0])}"
        except importlib.metadata.PackageNotFoundError:  # pragma: no cover - half-installed
            package = dists[0]
    digest = hashlib.sha256()
    files = _source_files(module_name)
    for f in files:
        try:
            digest.update(f.name.encode() + b"\0" + f.read_bytes() + b"\0")
        except OSError:  # a file gone since it was imported: its name still counts
            digest.update(f.name.encode())
    if not files:  # defined where no file is kept (an interpreter session)
        try:
            source = inspect.getsource(thing)
        except (OSError, TypeError):
            source = repr(getattr(thing, "__qualname__", thing))
        digest.update(source.encode())
    return {f"{kind}_origin": package, f"{kind}_code": digest.hexdigest()[:16]}


def replaced_origin(thing: Any, kind: str) -> dict[str, str]:
    """The identity of copi's own ``thing`` registered over another of copi's names (a
    sampler of one family as another, a method's class with other parameters): where it
    is defined, so that such a run never resumes into the name's own."""
    module_name = _defining_module(thing)
    what = getattr(thing, "__qualname__", None) or type(thing).__qualname__
    return {f"{kind}_origin": "copi (registered over copi's own)",
            f"{kind}_code": f"{module_name}:{what}"}  # fmt: skip


_NAME = re.compile(r"^[a-z0-9][a-z0-9_.-]*$")
"""A registered name: lower-case letters, digits, ``-``, ``_``, ``.`` (``@``, ``:``, ``+``
and ``/`` belong to the command line's grammar, never to a name)."""

T = TypeVar("T")


class Registry(Generic[T]):
    """Named things of one kind (methods, world families): copi's own, registered at
    import, and other packages', registered by their entry points (group ``group``) the
    first time a name is not found or the names are listed."""

    def __init__(self, kind: str, group: str, plural: str | None = None) -> None:
        self.kind = kind
        self.plural = plural or f"{kind}s"
        self.group = group
        self._items: dict[str, T] = {}
        self._own: frozenset[str] = frozenset()
        self._originals: dict[str, T] = {}
        self._replaced: set[str] = set()
        self._scanned = False

    def add(self, name: str, item: T, *, same: bool, replace: bool = False) -> T:
        """Register ``item`` as ``name``; a name taken is refused unless ``replace`` or
        ``same`` (the same registration again, which keeps the first)."""
        if not isinstance(name, str) or not _NAME.match(name):
            raise InvalidArgumentError(
                f"a {self.kind}'s name must be lower-case letters, digits, '-', '_' or '.'; "
                f"got {name!r}"
            )
        with _LOCK:
            old = self._items.get(name)
            if old is not None and not replace:
                if same:
                    return old
                raise InvalidArgumentError(
                    f"a {self.kind} named {name!r} is registered already; pass replace=True "
                    "to register over it"
                )
            if name in self._own:  # over one of copi's own, or putting it back
                if item is self._originals.get(name):
                    self._replaced.discard(name)
                else:
                    self._replaced.add(name)
            self._items[name] = item
        return item

    def replaced(self, name: str) -> bool:
        """Whether ``name``, one of copi's own, is registered over by another package."""
        return name in self._replaced and name in self._items

    def current(self, name: str) -> T | None:
        """What ``name`` is registered as now (entry points not consulted)."""
        return self._items.get(name)

    def seal(self) -> None:
        """What is registered now is copi's own: it cannot be removed."""
        self._own = frozenset(self._items)
        self._originals = dict(self._items)

    def original(self, name: str) -> T | None:
        """copi's own registration of ``name`` (to put it back), else None."""
        return self._originals.get(name)

    def remove(self, name: str) -> None:
        """Forget a registered name (e.g. one a test registered); copi's own stay (one
        registered over puts copi's back)."""
        with _LOCK:
            if name in self._replaced:
                self._items[name] = self._originals[name]
                self._replaced.discard(name)
                return
            if name in self._own:
                raise InvalidArgumentError(f"{name} is one of copi's own {self.plural}; it "
                                           "stays registered")  # fmt: skip
            self._items.pop(name, None)

    def get(self, name: str) -> T | None:
        """The item of ``name``, after the entry points have been loaded once in this
        process (another package may register over one of copi's own names: every
        command must see the same registration), and again when ``name`` is not
        registered (a package installed since); None when no one registers it."""
        if not self._scanned:
            self._scanned = True
            load_entry_points(self.group)
        item = self._items.get(name)
        if item is None:
            load_entry_points(self.group)
            item = self._items.get(name)
        return item

    def unknown(self, name: str) -> str:
        """The end of the message refusing ``name``: the entry points of this registry's
        group that could not be loaded (one of them may have been meant to register it)."""
        failed = failed_entry_points(self.group)
        if not failed:
            return ""
        return f" ({'; '.join(failed)}: it may have registered {name!r})"

    def names(self) -> tuple[str, ...]:
        """Every registered name: copi's own first, in the order registered."""
        self._scanned = True
        load_entry_points(self.group)
        return tuple(self._items)
