"""The registry mechanism: a method is an :class:`~copi.core.Agent` class (or any
callable returning one) plus one :func:`register_method` call, in the manner of
Gymnasium's ``register``. copi's own methods are registered by the catalogue
(:mod:`copi.methods._catalogue`), a user's by their package (see :mod:`copi.methods`).

A method's parameters are its factory's keyword defaults (updated by those given at
registration): a class's defaults are the values the registry and the docs use, tuned
on validation episodes (``studies/tune.py``, seed 1; the table is docs/tuning.md).
"""

from __future__ import annotations

import inspect
import json
import re
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from typing import Any

from copi._plugins import Registry, origin_of, replaced_origin
from copi.core import Agent, Sensing, check_sensing
from copi.errors import InvalidArgumentError
from copi.learning import Capabilities
from copi.results import LEGACY_NAMES

__all__ = [
    "ENTRY_POINTS",
    "REGISTRY",
    "MethodSpec",
    "default_methods",
    "make_agent",
    "method_names",
    "method_replaced",
    "method_spec",
    "methods_markdown",
    "register_method",
    "unregister_method",
]

ENTRY_POINTS = "copi.methods"
"""Entry-point group of third-party methods: each entry point names a callable taking no
argument that registers methods (``register_method``) when called. In ``pyproject.toml``::

    [project.entry-points."copi.methods"]
    mine = "my_package.copi_plugin:register"
"""


@dataclass(frozen=True)
class MethodSpec:
    """A registered method: how to build it, what it needs, what it is."""

    name: str
    factory: Callable[..., Agent]
    """Called as ``factory(**params)``, or ``factory(capabilities, **params)`` for a
    method that runs on capabilities."""
    sensing: Sensing
    """The least sensing level it needs."""
    levels: tuple[Sensing, ...]
    """Levels it runs at in the benchmark when its name is given alone."""
    summary: str
    """What it is, learnt versus hand-written."""
    params: dict[str, Any] = field(default_factory=dict)
    """Its parameters (JSON-able): the factory's keyword defaults, updated at
    registration. Part of every run's identity."""
    capabilities: str | None = None
    """The capability preset it runs on (copi's modes), else None."""
    requires: str | None = None
    """The optional extra it needs ("peers": navground; "rl": the RL extra), else None."""
    available: Callable[[], bool] = field(default=lambda: True, compare=False, repr=False)
    """Whether what it needs is installed."""
    missing: str = ""
    """What is missing when it is not available, and how to get it (one sentence)."""
    ablation: bool = False
    """An ablation of a copi mode: run when asked (``--methods ablations``)."""
    default: bool = False
    """Run by the benchmark when no method is named (copi's reference set)."""
    bound: bool = False
    """A bound on what is possible (a ceiling), not a method: marked so in every table."""
    inputs: Callable[[], dict[str, str]] | None = field(default=None, compare=False, repr=False)
    """Content hashes of the files the method reads (e.g. trained weights), by name: part
    of every run's identity, so that results of other weights never resume into it."""
    origin: dict[str, str] = field(default_factory=dict, compare=False)
    """Where the method comes from, for another package's: its package and version and a
    hash of its module's code (:func:`copi._plugins.origin_of`); empty for copi's own."""

    def input_hashes(self) -> dict[str, str]:
        """What the method's results depend on beyond its parameters, for every run's
        identity: where it comes from (:attr:`origin`) and the files it reads
        (:attr:`inputs`, called). Empty for copi's own methods that read no file."""
        origin = self.origin
        if not origin and REGISTRY.replaced(self.name):  # copi's own class under another name
            origin = replaced_origin(self.factory, "method")
            origin["method_code"] += " " + json.dumps(self.params, sort_keys=True)
        return {**origin, **({} if self.inputs is None else dict(self.inputs()))}

    def make(self, capabilities: Capabilities | None = None, **params: Any) -> Agent:
        """A fresh agent with the registered parameters, updated by ``params``."""
        unknown = sorted(set(params) - set(self.params))
        if unknown:
            raise InvalidArgumentError(
                f"{self.name} has no parameter {', '.join(unknown)}; its parameters are "
                f"{', '.join(sorted(self.params)) or 'none'}"
            )
        p = {**self.params, **params}
        if self.capabilities is not None:
            if capabilities is None:
                raise InvalidArgumentError(f"{self.name} needs a capabilities file")
            agent = self.factory(capabilities, **p)
        else:
            agent = self.factory(**p)
        if not isinstance(agent, Agent):
            raise InvalidArgumentError(
                f"the factory of {self.name} returned a {type(agent).__name__}, not a "
                "copi.core.Agent"
            )
        agent.name = self.name
        return agent


REGISTRY: Registry[MethodSpec] = Registry("method", ENTRY_POINTS)
"""Every registered method (the mechanism's one piece of state)."""


def _json_default(v: Any) -> bool:
    try:
        json.dumps(v)
    except (TypeError, ValueError):
        return False
    return v is not None


def _signature_params(factory: Callable[..., Any], skip_first: bool) -> dict[str, Any]:
    """The factory's keyword parameters with JSON-able defaults (``name`` aside)."""
    try:
        sig = inspect.signature(factory)
    except (TypeError, ValueError):
        return {}
    params = list(sig.parameters.values())
    if skip_first and params:
        params = params[1:]
    return {
        p.name: p.default
        for p in params
        if p.name != "name"
        and p.kind in (p.POSITIONAL_OR_KEYWORD, p.KEYWORD_ONLY)
        and p.default is not p.empty
        and _json_default(p.default)
    }


def register_method(
    name: str,
    factory: Callable[..., Agent],
    *,
    sensing: Sensing = "sensor",
    levels: Iterable[Sensing] | None = None,
    summary: str = "",
    params: dict[str, Any] | None = None,
    capabilities: str | None = None,
    requires: str | None = None,
    available: Callable[[], bool] | None = None,
    ablation: bool = False,
    default: bool = False,
    bound: bool = False,
    inputs: Callable[[], dict[str, str]] | None = None,
    missing: str = "",
    replace: bool = False,
) -> MethodSpec:
    """Register method ``name``: ``factory`` builds its :class:`~copi.core.Agent`.

    Parameters
    ----------
    name : str
        Lower-case letters, digits, ``-``, ``_`` and ``.``.
    factory : callable
        An Agent class, or a function returning an Agent; called with ``params`` as
        keywords (and the capabilities first, for ``capabilities``).
    sensing : {"sensor", "map", "oracle", "future"}
        The least level the method needs.
    levels : levels it runs at when named alone (default: ``sensor`` and ``map`` for a
        sensor-level method, else its own level).
    summary : what it is, learnt versus hand-written (shown in every method table).
    params : parameters to pass, over the factory's keyword defaults.
    capabilities : the capability preset it runs on (``faithful``, ``learnt``, ...).
    requires, available : an optional extra it needs, and whether it is installed.
    ablation, default, bound, inputs : see :class:`MethodSpec`.
    replace : register over an existing method of that name (otherwise refused, unless
        it is the same registration again).

    Examples
    --------
    >>> import numpy as np
    >>> from copi.core import Agent
    >>> class Still(Agent):
    ...     def __init__(self, *, speed=0.0): self.speed = speed
    ...     def reset(self, task): pass
    ...     def act(self, obs): return np.array([self.speed, 0.0])
    >>> spec = register_method("doc-still", Still, summary="stands still", replace=True)
    >>> spec.params, spec.levels, make_agent("doc-still").name
    ({'speed': 0.0}, ('sensor', 'map'), 'doc-still')
    >>> unregister_method("doc-still")
    """
    if not callable(factory):
        raise InvalidArgumentError(f"the factory of {name} must be callable; got {factory!r}")
    check_sensing(sensing)
    chosen: tuple[Sensing, ...] = (
        (("sensor", "map") if sensing == "sensor" else (sensing,))
        if levels is None
        else tuple(levels)
    )
    for lv in chosen:
        check_sensing(lv, sensing, method=name)
    extra = dict(params or {})
    for key, value in extra.items():
        if not _json_default(value) and value is not None:
            raise InvalidArgumentError(
                f"parameter {key} of {name} must be JSON-able; got {value!r}"
            )
    merged = {**_signature_params(factory, capabilities is not None), **extra}
    spec = MethodSpec(
        name=name, factory=factory, sensing=sensing, levels=chosen, summary=summary,
        params=merged, capabilities=capabilities, requires=requires,
        available=available or (lambda: True), ablation=ablation, default=default,
        bound=bound, inputs=inputs, origin=origin_of(factory, "method"),
        missing=missing or (f"the optional extra {requires!r}, which is not installed: pip "
                            f"install 'copi[{requires}]'" if requires else ""),
    )  # fmt: skip
    old = REGISTRY.current(name)
    same = old is not None and old.factory is factory and old.params == spec.params
    return REGISTRY.add(name, spec, same=same, replace=replace)


def unregister_method(name: str) -> None:
    """Remove a registered method (e.g. one a test registered); copi's own stay, and one
    registered over copi's own puts copi's back."""
    REGISTRY.remove(name)


def method_replaced(name: str) -> bool:
    """Whether ``name``, one of copi's own methods, is registered over by another
    package (``register_method(..., replace=True)``)."""
    return REGISTRY.replaced(name)


def method_names() -> tuple[str, ...]:
    """Every registered method's name, copi's modes first, then the baselines, peers and
    bounds, then those of other packages (in the order registered)."""
    return REGISTRY.names()


def methods_markdown() -> str:
    """The table of copi's built-in methods (name, levels, extra, what it is) as the README
    and the docs show it: generated, never typed (a test compares the README with it)."""
    rows = ["| method | levels | needs | what it is |", "|---|---|---|---|"]
    # one row for a series of methods that differ only by the family they were trained
    # on (ppo-star-map, ppo-crowd-map, ...): its name and summary with F for the family
    series: dict[tuple[str, ...], list[tuple[str, str, str]]] = {}
    for name in method_names():
        spec = method_spec(name)
        if spec.factory.__module__.split(".")[0] != "copi":
            continue  # another package's
        kind = " *(bound)*" if spec.bound else " *(ablation)*" if spec.ablation else ""
        extra = {"peers": "extra `peers`", "rl-weights": "shipped weights"}.get(
            spec.requires or "", "")
        parts = name.split("-")
        family = next((f for f in _SERIES_FAMILIES if f in parts), None)
        shown, summary = name, spec.summary
        if family is not None:
            shown = "-".join("F" if p == family else p for p in parts)
            summary = re.sub(rf"\b{family}\b", "F", summary)
        key = (shown, kind, ", ".join(spec.levels), extra, summary)
        series.setdefault(key, []).append((name, spec.summary, family or ""))
    for (shown, kind, levels, extra, summary), members in series.items():
        if len(members) == 1:  # alone: as it is
            shown, summary = members[0][0], members[0][1]
        else:
            summary = f"{summary} (F: {', '.join(m[2] for m in members)})"
        rows.append(f"| `{shown}`{kind} | {levels} | {extra} | {summary} |")
    return "\n".join(rows) + "\n"


_SERIES_FAMILIES = ("star", "polygon", "indoor", "maps", "crowd")
"""The families whose trained methods :func:`methods_markdown` shows a row a series."""


def method_spec(name: str) -> MethodSpec:
    """The spec of a method by name; an unknown name is refused, listing the known ones."""
    spec = REGISTRY.get(name)
    if spec is None:
        legacy = LEGACY_NAMES.get(name)
        hint = f" (now {legacy!r})" if legacy else ""
        raise InvalidArgumentError(
            f"method must be one of {', '.join(method_names())}; got {name!r}{hint}"
            f"{REGISTRY.unknown(name)}"
        )
    return spec


def make_agent(name: str, capabilities: Capabilities | None = None, **params: Any) -> Agent:
    """A fresh agent of method ``name`` with its registered parameters, updated by
    ``params``; copi's modes need their ``capabilities``."""
    spec = method_spec(name)
    if not spec.available():
        raise InvalidArgumentError(f"{name} needs {spec.missing or 'an optional extra'}")
    return spec.make(capabilities, **params)


def default_methods() -> tuple[str, ...]:
    """What the benchmark runs unless told otherwise."""
    return tuple(n for n in method_names() if method_spec(n).default)
