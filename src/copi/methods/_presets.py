"""copi's modes, whole: what ``copi learn --preset NAME`` learns and what every command
then runs with it, and the one place a command's preset, method and guard are settled.

A capabilities file says which preset it was learnt for by how it was learnt (its
directions, safety priors and contexts, :func:`preset_of`), so a command given only the
file runs the method it was learnt for, and a preset refuses every file learnt for
another mode.
The default preset is :data:`DEFAULT_PRESET` (the mode that works best); the paper's own
chain is one flag away (``--preset faithful``, which ``copi reproduce`` keeps for the
paper's tables).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any

from copi.errors import InvalidArgumentError
from copi.learning import Capabilities, LearnParams
from copi.methods._registry import method_spec

__all__ = [
    "DEFAULT_PRESET",
    "PRESETS",
    "Preset",
    "Resolved",
    "check_method_capabilities",
    "check_preset_capabilities",
    "preset",
    "preset_of",
    "resolve",
]


@dataclass(frozen=True)
class Preset:
    """One of copi's modes: the capabilities it learns and the method that runs them."""

    name: str
    learn: LearnParams
    """The capabilities it learns (seed 0 unless told otherwise)."""
    method: str
    """The registered method that runs them (its parameters, the guard among them, are
    the method's: :func:`copi.methods.method_spec`)."""
    summary: str

    @property
    def guard(self) -> float:
        """The hand-written guard's reach of the preset's method (0: none)."""
        return float(method_spec(self.method).params.get("guard", 0.0))


PRESETS: dict[str, Preset] = {
    p.name: p
    for p in [
        Preset("faithful", LearnParams(directions=4), "copi-faithful",
               "the paper's chain: 4 compass policies per template, no guard"),
        Preset("extended", LearnParams(directions=16), "copi-extended",
               "16 policies per template, each checked against the live reading by a "
               "hand-written guard (agent radius, an obstacle's step, a margin)"),
        Preset("learnt", LearnParams(directions=16, safety=True), "copi-learnt",
               "every compass direction scored by the route and by learnt safety (a network "
               "over the reading turned to the direction, trained on counterfactual probes "
               "of a task-free exploration); compass-guard's hand-written guard as a filter"),
        Preset("learnt-motion", LearnParams(directions=16, safety=True, motion=True),
               "copi-learnt-motion",
               "the learnt preset with contexts that see motion (the reading and its change) "
               "and the per-template safety priors over them added to each move's score"),
        Preset("predictive", LearnParams(directions=16, safety=True, safety_static=True,
                                         predict=True), "copi-predictive",
               "a learnt model of what moves (from the agent's own task-free walks) that the "
               "agent plans over, and the learnt safety network telling walls from what "
               "moves; no hand-written guard"),
    ]
}  # fmt: skip
"""copi's modes; the README says what each knows and what in it is learnt."""

DEFAULT_PRESET = "learnt"
"""The preset of ``copi learn`` and of the Python quickstart when none is named: the mode
that works best (see the benchmark); ``faithful`` is the paper's."""


def preset(name: str) -> Preset:
    """A preset by name; an unknown name is refused, listing the known ones."""
    try:
        return PRESETS[name]
    except KeyError:
        raise InvalidArgumentError(
            f"preset must be one of {', '.join(PRESETS)}; got {name!r}"
        ) from None


def _shape(caps: Capabilities) -> tuple[int, bool, bool, bool]:
    return (int(caps.policies.passable.shape[1]), caps.safety is not None, caps.motion,
            caps.motion_model is not None)  # fmt: skip


def preset_of(caps: Capabilities) -> str | None:
    """The preset ``caps`` were learnt for: the one whose directions, safety priors and
    contexts they have; None when no preset learns them (e.g. 8 directions)."""
    shape = _shape(caps)
    for name, p in PRESETS.items():
        if (p.learn.directions, p.learn.safety, p.learn.motion, p.learn.predict) == shape:
            return name
    return None


def _describe(shape: tuple[int, bool, bool, bool]) -> str:
    d, safety, motion, predict = shape
    parts = [f"{d} directions", "safety priors" if safety else "no safety priors"]
    if motion:
        parts.append("contexts that see motion")
    if predict:
        parts.append("a model of what moves")
    return ", ".join(parts)


def check_preset_capabilities(
    name: str, caps: Capabilities, where: str = "the file", *, who: str | None = None
) -> None:
    """Refuse capabilities not learnt the way preset ``name`` learns them (directions,
    safety priors, contexts that see motion), with one line saying how to learn the
    right ones. ``who``: the method that needs them (default: the preset)."""
    want = preset(name).learn
    need = (want.directions, want.safety, want.motion, want.predict)
    have = _shape(caps)
    if have == need:
        return
    learnt_for = preset_of(caps)
    as_what = f"preset {learnt_for}" if learnt_for else "no preset"
    raise InvalidArgumentError(
        f"{where} was learnt for {as_what} ({_describe(have)}); {who or f'preset {name}'} "
        f"needs {_describe(need)}: learn it with copi learn --preset {name}"
        + (f", or run it with --preset {learnt_for}" if learnt_for and who is None else "")
    )


@dataclass(frozen=True)
class Resolved:
    """What a command runs: a method and the parameters it sets over the method's."""

    method: str
    params: dict[str, Any] = dataclasses.field(default_factory=dict)
    preset: str | None = None


def resolve(
    *,
    preset_name: str | None = None,
    method: str | None = None,
    capabilities: Capabilities | None = None,
    where: str = "the file",
    guard: float | None = None,
) -> Resolved:
    """The one resolver of ``--preset``, ``--method``, a capabilities file and ``--guard``
    (``copi evaluate``, ``watch``, ``pursuit``).

    - ``--preset P``: P's method; a ``--method`` other than P's, a ``--guard`` other than
      P's, or a file learnt for another mode is refused.
    - ``--method M`` alone: M (its capabilities checked against its preset).
    - the file alone: the method of the preset it was learnt for.
    - ``--guard G`` without a preset: G over the method's guard (for methods that have
      one).

    Examples
    --------
    >>> resolve(method="dwa").method, resolve(preset_name="faithful").method
    ('dwa', 'copi-faithful')
    >>> try:
    ...     resolve(preset_name="learnt", guard=3.0)
    ... except InvalidArgumentError as err:
    ...     print(err)  # doctest: +ELLIPSIS
    --guard 3 contradicts --preset learnt (guard 1.05): drop --guard, or run --method ...
    """
    if guard is not None and not (math.isfinite(guard) and guard >= 0):
        raise InvalidArgumentError(f"guard must be a finite number >= 0; got {guard!r}")
    if preset_name is not None:
        p = preset(preset_name)
        if method is not None and method != p.method:
            raise InvalidArgumentError(
                f"--method {method} contradicts --preset {preset_name} ({p.method})"
            )
        if guard is not None and guard != p.guard:
            raise InvalidArgumentError(
                f"--guard {guard:g} contradicts --preset {preset_name} (guard {p.guard:g}): "
                f"drop --guard, or run --method {p.method} with --guard {guard:g}"
            )
        if capabilities is not None:
            check_preset_capabilities(preset_name, capabilities, where)
        return Resolved(p.method, {}, preset_name)
    if method is None:
        if capabilities is None:
            raise InvalidArgumentError(
                "give a capabilities file (for copi's modes), --preset NAME or --method NAME"
            )
        learnt_for = preset_of(capabilities)
        if learnt_for is None:
            raise InvalidArgumentError(
                f"{where} was learnt for no preset ({_describe(_shape(capabilities))}); name "
                "the method: --method copi-faithful or copi-extended"
            )
        method = PRESETS[learnt_for].method
    spec = method_spec(method)
    if spec.capabilities is not None:
        if capabilities is None:
            raise InvalidArgumentError(f"{method} needs a capabilities file")
        check_method_capabilities(method, capabilities, where)
    params: dict[str, Any] = {}
    if guard is not None:
        if "guard" not in spec.params:
            raise InvalidArgumentError(f"{method} has no guard; --guard applies to copi's modes "
                                       "and compass-guard")  # fmt: skip
        params["guard"] = float(guard)
    named = next((n for n, p in PRESETS.items() if p.method == method), None)
    return Resolved(method, params, named)


def check_method_capabilities(method: str, caps: Capabilities, where: str = "the file") -> None:
    """Refuse capabilities that method ``method`` cannot run as it is registered: they
    must have been learnt as its preset learns them (directions, safety priors, contexts
    that see motion); run otherwise, its results would be another method's under its
    name."""
    spec = method_spec(method)
    if spec.capabilities is not None:
        check_preset_capabilities(spec.capabilities, caps, where, who=method)
