"""Arms: a method run at a sensing level with a global strategy, written
``NAME[@LEVEL][:STRATEGY]`` on the command line; and the arms the experiments name."""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass

from copi.core import SENSING_LEVELS, Sensing, check_sensing, check_strategy
from copi.errors import InvalidArgumentError
from copi.methods._registry import default_methods, method_names, method_spec

__all__ = [
    "ABLATIONS",
    "LIFELONG_METHODS",
    "LIFELONG_REFERENCE",
    "MethodRun",
    "as_arms",
    "parse_lifelong_methods",
    "parse_methods",
]


@dataclass(frozen=True, order=True)
class MethodRun:
    """A method run at a sensing level with a global strategy (an experiment's arm)."""

    method: str
    sensing: Sensing
    strategy: str = "route"
    """"route" at levels with a map (the static route); at ``sensor`` one of
    :data:`copi.core.SENSOR_STRATEGIES`."""

    @property
    def label(self) -> str:
        """``method@sensing``, and ``:strategy`` at level sensor: ``dwa@map``,
        ``dwa@sensor:greedy``, ``copi-learnt@sensor:causal`` (the syntax
        :func:`parse_methods` reads)."""
        text = f"{self.method}@{self.sensing}"
        return text + (f":{self.strategy}" if self.sensing == "sensor" else "")


ABLATIONS = ("copi-learnt", "copi-learnt-priors", "copi-learnt-motion", "copi-learnt-persist",
             "compass-guard")  # fmt: skip
"""What ``--methods ablations`` stands for: copi-learnt, each of its ablations, and
compass-guard (copi-learnt with nothing learnt)."""


def parse_methods(
    text: str | None, *, strategy: str = "greedy", defaults: Iterable[str] | None = None
) -> list[MethodRun]:
    """``"dwa,copi-learnt@map,dwa@sensor:mapping"`` -> arms.

    ``NAME`` alone stands for every level the method runs at by default; ``@LEVEL`` for
    one level (checked against what the method needs); ``:STRATEGY`` sets the global
    strategy at level ``sensor`` (default ``strategy``; at ``map`` and ``oracle`` the
    route). ``ablations`` stands for :data:`ABLATIONS`; None for ``defaults`` (the
    benchmark's methods, :func:`default_methods`).

    Examples
    --------
    >>> [r.label for r in parse_methods("dwa@sensor:mapping,straight@map")]
    ['straight@map', 'dwa@sensor:mapping']
    """
    check_strategy(strategy)
    if text is None:
        items = list(default_methods() if defaults is None else defaults)
    else:
        items = [t.strip() for t in text.split(",") if t.strip()]
    items = [m for item in items for m in (ABLATIONS if item == "ablations" else (item,))]
    if not items:
        raise InvalidArgumentError("methods must name at least one method; got none")
    out: list[MethodRun] = []
    for item in items:
        head, colon, strat = item.partition(":")
        name, at, level = head.partition("@")
        if (at and not level) or (colon and not strat):
            raise InvalidArgumentError(
                f"{item}: name a level after @ ({', '.join(SENSING_LEVELS)}) and a strategy "
                "after : (greedy, mapping, causal), as in dwa@sensor:mapping"
            )
        spec = method_spec(name)
        levels = [level] if level else list(spec.levels)
        if strat:
            check_strategy(strat)
        for lv in levels:
            check_sensing(lv, spec.sensing, method=name)
            if lv != "sensor" and strat:
                raise InvalidArgumentError(
                    f"{item}: a global strategy is chosen at level sensor only (at {lv} the "
                    f"method follows the route): write {name}@sensor:{strat}"
                )
            run = MethodRun(name, lv, (strat or strategy) if lv == "sensor" else "route")  # type: ignore[arg-type]
            if run not in out:
                out.append(run)
    order = {n: i for i, n in enumerate(method_names())}
    return sorted(out, key=lambda r: (order[r.method], SENSING_LEVELS.index(r.sensing),
                                      r.strategy))  # fmt: skip


def as_arms(
    items: Iterable[MethodRun | str],
    parse: Callable[[str], Iterable[MethodRun]] | None = None,
) -> tuple[MethodRun, ...]:
    """Arms given as :class:`MethodRun` or as text (``"dwa@sensor:mapping"``, read by
    ``parse``, default :func:`parse_methods`), once each, in order."""
    read = parse or parse_methods
    out: list[MethodRun] = []
    for item in items:
        runs = list(read(item)) if isinstance(item, str) else [item]
        for run in runs:
            if not isinstance(run, MethodRun):
                raise InvalidArgumentError(f"methods must be MethodRun arms; got {run!r}")
        out += runs
    return tuple(dict.fromkeys(out))


LIFELONG_METHODS: dict[str, str] = {
    "copi-learnt@sensor:causal": "the learnt preset planning over its causal map and "
    "occupancy grid, both kept from task to task",
    "copi-learnt-continual@sensor:causal": "as copi-learnt with the causal strategy, also "
    "growing contexts for unfamiliar readings",
    "copi-learnt@sensor:mapping": "the learnt preset following its occupancy grid (kept), no "
    "causal map",
    "compass-guard@sensor:mapping": "compass-guard following its occupancy grid (kept)",
    "dwa@sensor:mapping": "DWA following its occupancy grid (kept)",
    "copi-learnt@map": "the learnt preset given the static map (the route): the yardstick "
    "the sensor-level agent should reach",
}
"""Experiment 3's arms (method, level, strategy), copi's first, and what each keeps."""


LIFELONG_REFERENCE = MethodRun("copi-learnt", "sensor", "causal")
"""The arm every other arm of Experiment 3 is paired against."""


def parse_lifelong_methods(text: str | None) -> tuple[MethodRun, ...]:
    """``"copi-learnt@sensor:causal,dwa@sensor:mapping"`` -> arms; None: all of
    :data:`LIFELONG_METHODS`. A method named alone runs at ``sensor`` with the ``causal``
    strategy (copi's) or ``mapping`` (methods without contexts keep only a grid)."""
    items = list(LIFELONG_METHODS) if text is None else [
        t.strip() for t in text.split(",") if t.strip()
    ]  # fmt: skip
    if not items:
        raise InvalidArgumentError("methods must name at least one method; got none")
    out: list[MethodRun] = []
    for item in items:
        if "@" not in item and ":" not in item:
            spec = method_spec(item)
            item = f"{item}@sensor:{'causal' if spec.capabilities else 'mapping'}"
        for run in parse_methods(item):
            if run not in out:
                out.append(run)
    return tuple(out)
