"""Every navigating method by name: the registry copi's modes, the baselines and the
peers are in, and that a user's method joins with one call.

A method is an :class:`~copi.core.Agent` class (or any callable returning one) plus one
:func:`register_method` call, in the manner of Gymnasium's ``register``::

    from copi.core import Agent
    from copi.experiments import register_method

    class Eastward(Agent):
        name = "eastward"
        def reset(self, task): ...
        def act(self, obs): return np.array([1.0, 0.0])

    register_method("eastward", Eastward, summary="always east (hand-written)")

after which ``copi benchmark --methods eastward`` runs it on the same episodes as every
other method. A package makes its methods known to the command line through the entry
point group ``copi.methods`` (each entry point names a function that registers them;
see :data:`ENTRY_POINTS`). :func:`copi.testing.check_agent` checks a method keeps the
contract.

A method's parameters are its factory's keyword defaults (updated by those given at
registration): a class's defaults are the values the registry and the docs use, tuned
on validation episodes (``benchmarks/tune.py``, seed 1; the table is docs/tuning.md).

In an experiment a method runs at a sensing level with a global strategy: an *arm*,
written ``NAME[@LEVEL][:STRATEGY]`` on the command line (:func:`parse_methods`), whose
three fields are stored apart in every result row.
"""

from __future__ import annotations

import inspect
import json
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from typing import Any

from copi._plugins import Registry
from copi.baselines import (
    DWA,
    NAVGROUND_BEHAVIORS,
    VFH,
    CompassGuard,
    NavgroundAgent,
    PPOAgent,
    Replan,
    Straight,
    TangentBug,
    TrackedMPC,
    navground_available,
    packaged_policy,
)
from copi.ceilings import Clairvoyant, ModelOracle
from copi.core import SENSING_LEVELS, Agent, Sensing, check_sensing, check_strategy
from copi.errors import InvalidArgumentError
from copi.learning import Capabilities
from copi.online import CopiAgent, LearntAgent

__all__ = [
    "ABLATIONS",
    "methods_markdown",
    "ENTRY_POINTS",
    "LEGACY_NAMES",
    "MethodRun",
    "MethodSpec",
    "as_arms",
    "check_method_capabilities",
    "default_methods",
    "make_agent",
    "method_names",
    "method_spec",
    "parse_methods",
    "register_method",
    "split_legacy_name",
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

    def input_hashes(self) -> dict[str, str]:
        """:attr:`inputs`, called (empty for a method that reads no file)."""
        return {} if self.inputs is None else dict(self.inputs())

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


_REGISTRY: Registry[MethodSpec] = Registry("method", ENTRY_POINTS)


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
        bound=bound, inputs=inputs,
        missing=missing or (f"the optional extra {requires!r}, which is not installed: pip "
                            f"install 'copi[{requires}]'" if requires else ""),
    )  # fmt: skip
    old = _REGISTRY.current(name)
    same = old is not None and old.factory is factory and old.params == spec.params
    return _REGISTRY.add(name, spec, same=same, replace=replace)


def unregister_method(name: str) -> None:
    """Remove a registered method (e.g. one a test registered); copi's own stay."""
    _REGISTRY.remove(name)


def method_names() -> tuple[str, ...]:
    """Every registered method's name, copi's modes first, then the baselines, peers and
    bounds, then those of other packages (in the order registered)."""
    return _REGISTRY.names()


def methods_markdown() -> str:
    """The table of copi's built-in methods (name, levels, extra, what it is) as the README
    and the docs show it: generated, never typed (a test compares the README with it)."""
    rows = ["| method | levels | needs | what it is |", "|---|---|---|---|"]
    for name in method_names():
        spec = method_spec(name)
        if spec.factory.__module__.split(".")[0] != "copi":
            continue  # another package's
        kind = " *(bound)*" if spec.bound else " *(ablation)*" if spec.ablation else ""
        extra = {"peers": "extra `peers`", "rl-weights": "shipped weights"}.get(
            spec.requires or "", "")
        rows.append(f"| `{name}`{kind} | {', '.join(spec.levels)} | {extra} | {spec.summary} |")
    return "\n".join(rows) + "\n"


def method_spec(name: str) -> MethodSpec:
    """The spec of a method by name; an unknown name is refused, listing the known ones."""
    spec = _REGISTRY.get(name)
    if spec is None:
        legacy = LEGACY_NAMES.get(name)
        hint = f" (now {legacy!r})" if legacy else ""
        raise InvalidArgumentError(
            f"method must be one of {', '.join(method_names())}; got {name!r}{hint}"
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


# -- arms: a method at a level with a global strategy ---------------------------------


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
        head, _, strat = item.partition(":")
        name, _, level = head.partition("@")
        spec = method_spec(name)
        levels = [level] if level else list(spec.levels)
        if strat:
            check_strategy(strat)
        for lv in levels:
            check_sensing(lv, spec.sensing, method=name)
            if lv != "sensor" and strat:
                raise InvalidArgumentError(
                    f"{item}: a global strategy is chosen at level sensor only (at {lv} the "
                    "method follows the route)"
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


LEGACY_NAMES = {
    "copi-learnt+priors": "copi-learnt-priors",
    "copi-learnt+motion": "copi-learnt-motion",
    "copi-learnt+persist": "copi-learnt-persist",
}
"""Method names of stores written by copi 0.2 and their names now."""

_LEGACY_LIFELONG = {
    "copi-learnt+causal": ("copi-learnt", "sensor", "causal"),
    "copi-learnt+causal+continual": ("copi-learnt-continual", "sensor", "causal"),
    "copi-learnt+mapping": ("copi-learnt", "sensor", "mapping"),
    "compass-guard+mapping": ("compass-guard", "sensor", "mapping"),
    "dwa+mapping": ("dwa", "sensor", "mapping"),
    "copi-learnt@map": ("copi-learnt", "map", "route"),
}


def split_legacy_name(name: str) -> tuple[str, str | None, str | None]:
    """(method, sensing, strategy) of a method label an older store holds, where the
    label carried them (``dwa+mapping``, ``copi-learnt@map``); None where it did not.

    Examples
    --------
    >>> split_legacy_name("dwa+mapping"), split_legacy_name("copi-learnt+priors")
    (('dwa', 'sensor', 'mapping'), ('copi-learnt-priors', None, None))
    """
    if name in _LEGACY_LIFELONG:
        return _LEGACY_LIFELONG[name]
    return LEGACY_NAMES.get(name, name), None, None


# -- capabilities each method needs ---------------------------------------------------


def check_method_capabilities(method: str, caps: Capabilities, where: str = "the file") -> None:
    """Refuse capabilities that method ``method`` cannot run as it is registered: they
    must have been learnt as its preset learns them (directions, safety priors, contexts
    that see motion); run otherwise, its results would be another method's under its
    name."""
    spec = method_spec(method)
    if spec.capabilities is not None:
        from copi.experiments.presets import check_preset_capabilities

        check_preset_capabilities(spec.capabilities, caps, where, who=method)


# -- copi's modes, the baselines and the peers ----------------------------------------


def _navground(behavior: str) -> Callable[..., Agent]:
    def make(*, safety_margin: float = 0.3, horizon: float = 5.0) -> Agent:
        return NavgroundAgent(behavior, safety_margin=safety_margin, horizon=horizon)

    make.__name__ = f"navground_{behavior.lower()}"
    return make


_RL_POLICIES = [
    ("ppo", "ppo-mix", 0.0, "a local policy learnt by PPO (deep RL, 2M steps) on all five "
     "families, under the level's global direction; nothing hand-written"),
    ("ppo-guard", "ppo-mix", 1.05, "ppo shielded by compass-guard's hand-written guard"),
    *[(f"ppo-{f}", f"ppo-{f}", 0.0, f"PPO trained on the {f} family only")
      for f in ("star", "polygon", "indoor", "maps", "crowd")],
    ("ppo-chauffeur", "ppo-chauffeur", 0.0, "PPO trained as the evader of the homicidal "
     "chauffeur (Experiment 2), under the game's direction"),
]  # fmt: skip


def _weights_present(weights: str) -> Callable[[], bool]:
    return lambda: packaged_policy(weights).is_file()


def _weights_hash(weights: str) -> Callable[[], dict[str, str]]:
    def sha() -> dict[str, str]:
        from copi.experiments._runs import file_sha

        path = packaged_policy(weights)
        return {"weights_sha": file_sha(path)} if path.is_file() else {}

    return sha


def _register_builtins() -> None:
    # Every parameter below equals its class's default: tuned by benchmarks/tune.py
    # (validation seed 1, all five families, 40 episodes each, four settings per method;
    # the table is docs/tuning.md). navground's ORCA was not tuned.
    reg = register_method
    reg("copi-faithful", CopiAgent, capabilities="faithful", default=True,
        summary="the paper's chain: learnt contexts, landmarks, symmetry and 4 A* policies "
        "per template; no hand-written avoidance")
    reg("copi-extended", CopiAgent, capabilities="extended", default=True,
        params={"guard": 1.05},
        summary="the chain with 16 policies per template; each candidate checked against the "
        "live reading by a hand-written guard, which escapes when none is safe")
    reg("copi-learnt", LearntAgent, capabilities="learnt", default=True,
        summary="16 compass moves scored by the route and by learnt safety (a network over "
        "the reading turned to each move, trained on counterfactual probes of a task-free "
        "exploration, shared by every direction through the symmetry); compass-guard's "
        "hand-written guard kept as a filter")
    # The learnt preset's ablations: -priors and -persist differ from copi-learnt in one
    # thing each, -motion from -priors in its contexts and its prior weight;
    # compass-guard is copi-learnt with nothing learnt (alpha = beta = 0), its guard
    # tuned on its own. Every weight: docs/tuning.md.
    reg("copi-learnt-priors", LearntAgent, capabilities="learnt", ablation=True,
        params={"beta": 1.0},
        summary="copi-learnt plus the per-template safety priors (contexts of the reading "
        "alone, each move read through the template's symmetry) in each move's score")
    reg("copi-learnt-motion", LearntAgent, capabilities="learnt-motion", ablation=True,
        params={"beta": 0.5},
        summary="copi-learnt-priors with contexts that see motion: context map, landmarks, "
        "templates and their priors over [reading, its change]")
    reg("copi-learnt-persist", LearntAgent, capabilities="learnt", ablation=True,
        params={"persist": 0.05},
        summary="copi-learnt whose last move scores more while the reading stays within its "
        "landmark (policies that last, paper §V)")
    reg("copi-learnt-continual", LearntAgent, capabilities="learnt",
        params={"continual": True},
        summary="copi-learnt growing contexts for unfamiliar readings online (paper §II-A, "
        "§III); in a lifelong run the grown contexts are kept")
    reg("straight", Straight, default=True,
        summary="the global direction, no avoidance (hand-written, nothing tuned)")
    reg("compass-guard", CompassGuard, default=True,
        summary="copi-extended's hand-written guard over 16 compass moves, no capabilities "
        "(ablation of the learnt part)")
    reg("vfh", VFH, default=True,
        summary="Vector Field Histogram (VFH+) on the ranges (hand-written)")
    reg("dwa", DWA, default=True,
        summary="Dynamic Window: sampled velocities scored on the ranges (hand-written)")
    reg("tangent-bug", TangentBug, default=True,
        summary="TangentBug on the ranges (hand-written)")
    # the model-oracle's planner on what a map-level agent makes out (0.3-3 s an episode,
    # so run apart like model-oracle: --methods tracked-mpc)
    reg("tracked-mpc", TrackedMPC, sensing="map", default=False,
        summary="model-predictive control (the model-oracle's planner) on the discs it makes "
        "out in its reading (circle fits of the hits the map does not explain, velocities "
        "from their last displacement), their speed and turn spread estimated from its own "
        "tracks (hand-written; nothing learnt offline)")
    reg("replan", Replan, sensing="oracle", default=True,
        summary="shortest path on the current snapshot, obstacles inflated, re-planned "
        "(hand-written; sees every obstacle)")
    # Learnt by deep RL on copi's episodes (copi rl train; the weights ship in
    # copi/data/rl with the commands that trained them). A policy absent is left out.
    for name, weights, guard, summary in _RL_POLICIES:
        reg(name, PPOAgent, default=name in ("ppo", "ppo-guard"), requires="rl-weights",
            available=_weights_present(weights), inputs=_weights_hash(weights),
            params={"weights": weights, "guard": guard}, summary=summary,
            missing=f"its trained weights {weights}.npz, which copi does not ship here: train "
            f"them with copi rl train -o {weights}.npz (docs: copi against deep RL)")
    # Bounds, not methods: what is possible (marked so in every table and figure).
    reg("clairvoyant", Clairvoyant, sensing="future", default=True, bound=True,
        summary="a bound: space-time A* on the obstacles' recorded future (they ignore the "
        "agent), its plan replayed through the simulator: the share of episodes solvable")
    # model-oracle costs 0.2-2 s an episode (10-20 ms a step): not in the default run; run it
    # on fewer episodes into the same directory, the report pairs it on those.
    reg("model-oracle", ModelOracle, sensing="oracle", default=False, bound=True,
        summary="a bound: model-predictive control on 32 sampled futures of the obstacles' "
        "random walk (its true parameters), each solved in hindsight and the costs averaged, "
        "replanned every step; knows the present and the motion model, not the future "
        "(hand-written, tuned on seed 1; 1-3 s an episode, so run apart: --methods "
        "model-oracle)")
    margins = {"navground-hrvo": 0.6, "navground-hl": 0.3, "navground-orca": 0.3}
    for name, behavior in NAVGROUND_BEHAVIORS.items():
        reg(name, _navground(behavior), sensing="oracle", requires="peers",
            available=navground_available, default=name != "navground-orca",
            missing="navground, which is not installed: pip install 'copi[peers]'",
            params={"safety_margin": margins[name]},
            summary=f"navground's {behavior} (sees obstacle positions and velocities)")
    # fmt: skip


_register_builtins()
_REGISTRY.seal()
