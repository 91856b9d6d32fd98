"""Every navigating method by name: copi's modes and the baselines, what each knows, what
in it is learnt, and its parameters (tuned on validation episodes, see ``TUNING``)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from copi.baselines import (
    DWA,
    NAVGROUND_BEHAVIORS,
    VFH,
    CompassGuard,
    NavgroundAgent,
    NavgroundMissingError,
    Replan,
    Straight,
    TangentBug,
    navground_available,
)
from copi.errors import InvalidArgumentError
from copi.learning import Capabilities, LearnParams
from copi.online import SENSING_LEVELS, Agent, CopiAgent, LearntAgent, check_sensing

__all__ = [
    "ABLATIONS",
    "CAPABILITY_PRESETS",
    "PRESETS",
    "Preset",
    "check_method_capabilities",
    "check_preset_capabilities",
    "preset",
    "METHODS",
    "MethodSpec",
    "make_agent",
    "method_spec",
    "parse_methods",
]


@dataclass(frozen=True)
class Preset:
    """One of copi's modes, whole: what ``copi learn --preset NAME`` learns and what
    ``copi evaluate`` / ``copi pursuit --preset NAME`` then run with it."""

    name: str
    learn: LearnParams
    """The capabilities it learns (seed 0 unless told otherwise)."""
    method: str
    """The method ``evaluate --preset`` runs."""
    guard: float
    """The hand-written guard's reach (0: none)."""
    summary: str


PRESETS: dict[str, Preset] = {
    p.name: p
    for p in [
        Preset("faithful", LearnParams(directions=4), "copi-faithful", 0.0,
               "the paper's chain: 4 compass policies per template, no guard"),
        Preset("extended", LearnParams(directions=16), "copi-extended", 1.2,
               "16 policies per template, each checked against the live reading by a "
               "hand-written guard of 1.2 (agent radius, an obstacle's step, a margin)"),
        Preset("learnt", LearnParams(directions=16, safety=True), "copi-learnt", 1.05,
               "every compass direction scored by the route and by learnt safety (a network "
               "over the reading turned to the direction, trained on counterfactual probes "
               "of a task-free exploration); compass-guard's hand-written guard as a filter"),
        Preset("learnt-motion", LearnParams(directions=16, safety=True, motion=True),
               "copi-learnt+motion", 1.05,
               "the learnt preset with contexts that see motion (the reading and its change) "
               "and the per-template safety priors over them added to each move's score"),
    ]
}  # fmt: skip
"""copi's modes; the README says what each knows and what in it is learnt."""

CAPABILITY_PRESETS: dict[str, LearnParams] = {n: p.learn for n, p in PRESETS.items()}
"""Capabilities each copi mode learns (seed 0 unless told otherwise): the paper's four
compass policies per template, or sixteen."""


def preset(name: str) -> Preset:
    """A preset by name; an unknown name is refused, listing the known ones."""
    try:
        return PRESETS[name]
    except KeyError:
        raise InvalidArgumentError(
            f"preset must be one of {', '.join(PRESETS)}; got {name!r}"
        ) from None


def _check_learnt_like(
    caps: Capabilities, want: LearnParams, who: str, preset_name: str, where: str
) -> None:
    """Refuse capabilities without the safety priors ``want`` asks for, or whose contexts
    see motion when ``want``'s do not (or the reverse); ``who`` needs them."""
    if want.safety and caps.safety is None:
        raise InvalidArgumentError(
            f"{where} has no safety priors; {who} needs them: learn it with "
            f"copi learn --preset {preset_name}"
        )
    if caps.motion != want.motion:
        which = "with" if caps.motion else "without"
        raise InvalidArgumentError(
            f"{where} was learnt {which} contexts that see motion; {who} needs "
            f"{'them' if want.motion else 'none'}: learn it with copi learn --preset "
            f"{preset_name}"
        )


def check_method_capabilities(method: str, caps: Capabilities, where: str = "the file") -> None:
    """Refuse capabilities that method ``method`` cannot run as it is registered: a learnt
    method needs safety priors, and its contexts see motion exactly when its preset's do
    (run otherwise, its results would be another method's under its name)."""
    spec = method_spec(method)
    if spec.capabilities is not None:
        _check_learnt_like(caps, CAPABILITY_PRESETS[spec.capabilities], method,
                           spec.capabilities, where)  # fmt: skip


def check_preset_capabilities(name: str, caps: Capabilities, where: str = "the file") -> None:
    """Refuse capabilities that were not learnt the way preset ``name`` needs, with one
    line saying how to learn the right ones."""
    want = preset(name).learn
    _check_learnt_like(caps, want, f"preset {name}", name, where)
    have = int(caps.policies.passable.shape[1])
    if have != want.directions:
        raise InvalidArgumentError(
            f"{where} was learnt with {have} directions; preset {name} needs "
            f"{want.directions}: learn it with copi learn --preset {name}"
        )


@dataclass(frozen=True)
class MethodSpec:
    """A method: how to build it, what it needs, what it is."""

    name: str
    sensing: str
    """The least sensing level it needs."""
    levels: tuple[str, ...]
    """Levels it runs at in the benchmark by default."""
    summary: str
    """What it is, learnt versus hand-written."""
    params: dict[str, Any] = field(default_factory=dict)
    """Its parameters (tuned values where tuned)."""
    capabilities: str | None = None
    """The capability preset it needs (copi's modes), else None."""
    optional: bool = False
    """Needs an optional extra (navground)."""
    ablation: bool = False
    """An ablation of a copi mode: run when asked (``--methods ablations``), not by default."""

    @property
    def available(self) -> bool:
        return not self.optional or navground_available()


_MAP_AND_SENSOR = ("sensor", "map")

# Every registered parameter below was tuned by benchmarks/tune.py (validation seed 1,
# all five families, 40 episodes each, four settings per method; the table is
# docs/tuning.md). navground's ORCA was not tuned.
_NAVGROUND_MARGIN = {"navground-hrvo": 0.6, "navground-hl": 0.3}
_LEARNT: dict[str, Any] = {"guard": 1.05, "alpha": 2.0, "beta": 0.0, "wait": False}
_BETA_PRIORS = 0.5
_BETA_MOTION = 0.25
"""Weights of the template priors in the ablations that use them: each chosen among 0.25,
0.5, 1 and 2 by benchmarks/tune.py (validation seed 1; the table is docs/tuning.md)."""
_PERSIST = 0.05
"""Persistence bonus of copi-learnt+persist (the smaller of the two validated, see the
README: the larger cost up to 5 points of success)."""

METHODS: dict[str, MethodSpec] = {
    spec.name: spec
    for spec in [
        MethodSpec(
            "copi-faithful", "sensor", _MAP_AND_SENSOR,
            "the paper's chain: learnt contexts, landmarks, symmetry and 4 A* policies per "
            "template; no hand-written avoidance",
            {"guard": 0.0}, capabilities="faithful",
        ),
        MethodSpec(
            "copi-extended", "sensor", _MAP_AND_SENSOR,
            "the chain with 16 policies per template; each candidate checked against the live "
            "reading by a hand-written guard, which escapes when none is safe",
            {"guard": 1.2}, capabilities="extended",
        ),
        MethodSpec(
            "copi-learnt", "sensor", _MAP_AND_SENSOR,
            "16 compass moves scored by the route and by learnt safety (a network over the "
            "reading turned to each move, trained on counterfactual probes of a task-free "
            "exploration, shared by every direction through the symmetry); compass-guard's "
            "hand-written guard kept as a filter",
            _LEARNT, capabilities="learnt",
        ),
        # The learnt preset's ablations: +priors and +persist differ from copi-learnt in
        # one thing each, +motion from +priors in one (its contexts); compass-guard is
        # copi-learnt with nothing learnt (alpha = beta = 0).
        MethodSpec(
            "copi-learnt+priors", "sensor", _MAP_AND_SENSOR,
            "copi-learnt plus the per-template safety priors (contexts of the reading "
            "alone, each move read through the template's symmetry) in each move's score",
            {**_LEARNT, "beta": _BETA_PRIORS}, capabilities="learnt", ablation=True,
        ),
        MethodSpec(
            "copi-learnt+motion", "sensor", _MAP_AND_SENSOR,
            "copi-learnt+priors with contexts that see motion: context map, landmarks, "
            "templates and their priors over [reading, its change]",
            {**_LEARNT, "beta": _BETA_MOTION}, capabilities="learnt-motion", ablation=True,
        ),
        MethodSpec(
            "copi-learnt+persist", "sensor", _MAP_AND_SENSOR,
            "copi-learnt whose last move scores more while the reading stays within its "
            "landmark (policies that last, paper §V)",
            {**_LEARNT, "persist": _PERSIST}, capabilities="learnt", ablation=True,
        ),
        MethodSpec(
            "straight", "sensor", _MAP_AND_SENSOR,
            "the global direction, no avoidance (hand-written, nothing tuned)",
        ),
        MethodSpec(
            "compass-guard", "sensor", _MAP_AND_SENSOR,
            "copi-extended's hand-written guard over 16 compass moves, no capabilities "
            "(ablation of the learnt part)",
            {"guard": 1.05},
        ),
        MethodSpec(
            "vfh", "sensor", _MAP_AND_SENSOR,
            "Vector Field Histogram (VFH+) on the ranges (hand-written)",
            {"threshold": 0.5, "safety": 0.5},
        ),
        MethodSpec(
            "dwa", "sensor", _MAP_AND_SENSOR,
            "Dynamic Window: sampled velocities scored on the ranges (hand-written)",
            {"margin": 0.9, "clearance_weight": 0.3},
        ),
        MethodSpec(
            "tangent-bug", "sensor", _MAP_AND_SENSOR,
            "TangentBug on the ranges (hand-written)",
            {"margin": 0.5, "follow": 1.0},
        ),
        MethodSpec(
            "replan", "oracle", ("oracle",),
            "shortest path on the current snapshot, obstacles inflated, re-planned "
            "(hand-written; sees every obstacle)",
            {"inflate": 0.6},
        ),
        *[
            MethodSpec(
                name, "oracle", ("oracle",),
                f"navground's {behavior} (sees obstacle positions and velocities)",
                {"safety_margin": _NAVGROUND_MARGIN.get(name, 0.3), "horizon": 5.0},
                optional=True,
            )
            for name, behavior in NAVGROUND_BEHAVIORS.items()
        ],
    ]
}  # fmt: skip
"""The registry: copi's modes first, then the baselines and peers."""

DEFAULT_METHODS = tuple(
    n for n, s in METHODS.items() if n != "navground-orca" and not s.ablation
)
"""Methods the benchmark runs unless told otherwise (navground's ORCA is optional; the
ablations run when asked)."""

ABLATIONS = ("copi-learnt", *(n for n, s in METHODS.items() if s.ablation), "compass-guard")
"""What ``--methods ablations`` stands for: copi-learnt, each of its ablations, and
compass-guard (copi-learnt with nothing learnt)."""


def method_spec(name: str) -> MethodSpec:
    """The spec of a method by name; an unknown name is refused, listing the known ones."""
    try:
        return METHODS[name]
    except KeyError:
        raise InvalidArgumentError(
            f"method must be one of {', '.join(METHODS)}; got {name!r}"
        ) from None


def parse_methods(text: str | None) -> list[tuple[str, str]]:
    """``"dwa,copi-extended@map"`` -> [(method, level), ...]: a bare name stands for
    every level the method runs at by default; ``name@level`` for one level (checked
    against what the method needs); ``ablations`` for :data:`ABLATIONS`. None: every
    default method at its levels."""
    items = DEFAULT_METHODS if text is None else [t.strip() for t in text.split(",") if t.strip()]
    items = [m for item in items for m in (ABLATIONS if item == "ablations" else (item,))]
    if not items:
        raise InvalidArgumentError("methods must name at least one method; got none")
    out: list[tuple[str, str]] = []
    for item in items:
        name, _, level = item.partition("@")
        spec = method_spec(name)
        levels = [level] if level else list(spec.levels)
        for lv in levels:
            check_sensing(lv, spec.sensing, method=name)
            if (name, lv) not in out:
                out.append((name, lv))
    order = {n: i for i, n in enumerate(METHODS)}
    return sorted(out, key=lambda m: (order[m[0]], SENSING_LEVELS.index(m[1])))


def make_agent(name: str, capabilities: Capabilities | None = None, **params: Any) -> Agent:
    """A fresh agent of method ``name`` with its registered parameters, updated by
    ``params``; copi's modes need their ``capabilities``."""
    spec = method_spec(name)
    p = {**spec.params, **params}
    if spec.capabilities is not None:
        if capabilities is None:
            raise InvalidArgumentError(f"{name} needs a capabilities file")
        if CAPABILITY_PRESETS[spec.capabilities].safety:  # the learnt presets
            return LearntAgent(capabilities, name=name, guard=float(p["guard"]),
                               alpha=float(p["alpha"]), beta=float(p["beta"]),
                               wait=bool(p["wait"]),
                               continual=bool(p.get("continual", False)),
                               grow_every=int(p.get("grow_every", 20)),
                               persist=float(p.get("persist", 0.0)))  # fmt: skip
        return CopiAgent(capabilities, name=name, guard=float(p.get("guard", 0.0)),
                         continual=bool(p.get("continual", False)))  # fmt: skip
    if spec.optional and not navground_available():
        raise NavgroundMissingError(
            f"{name} needs navground, which is not installed: pip install 'copi[peers]'"
        )
    factories: dict[str, Any] = {
        "straight": Straight,
        "compass-guard": CompassGuard,
        "vfh": VFH,
        "dwa": DWA,
        "tangent-bug": TangentBug,
        "replan": Replan,
    }
    if name in NAVGROUND_BEHAVIORS:
        return NavgroundAgent(NAVGROUND_BEHAVIORS[name], **p)
    agent: Agent = factories[name](**p)
    return agent
