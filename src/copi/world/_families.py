"""World families of the benchmark, each drawn from a seed and reachable by name."""

from __future__ import annotations

import os
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import shapely
from shapely.geometry import LineString

from copi._plugins import Registry, origin_of, replaced_origin
from copi._rng import Seed, as_generator
from copi._validation import as_vector
from copi.errors import CopiError, InvalidArgumentError, ctrl_c_behind
from copi.world._family_crowdnav import (
    CROWDNAV,
    STEPS_PER_METRE,
    circle_crossing,
    square_crossing,
)
from copi.world._family_indoor import indoor_world
from copi.world._family_maps import MapsParams, map_window_world, maps_identity
from copi.world._family_polygon import polygon_world
from copi.world._generate import random_world
from copi.world._world import ObstacleSpec, World

__all__ = [
    "CROWD_OBSTACLES",
    "ENTRY_POINTS",
    "EpisodeSettings",
    "FAMILIES",
    "FamilySpec",
    "check_family",
    "family_inputs",
    "family_names",
    "family_replaced",
    "family_spec",
    "in_sight",
    "register_family",
    "sample_world",
    "unregister_family",
]

FAMILIES = ("circle-crossing", "crowd", "indoor", "maps", "polygon", "square-crossing", "star")
"""Names of copi's own world families, sorted (see :func:`sample_world`); other packages
add theirs with :func:`register_family` (all of them: :func:`family_names`)."""

CROWD_OBSTACLES = ObstacleSpec(count=(25, 40), radius=(0.5, 1.0), speed=0.8)
"""Moving obstacles of the ``crowd`` family: denser and faster than the paper's."""

ENTRY_POINTS = "copi.families"
"""Entry-point group of third-party world families: each entry point names a callable
taking no argument that registers families (:func:`register_family`) when called."""

Sampler = Callable[..., World]
"""sampler(rng, *, name=None) -> World: a family's world drawn from the generator."""


@dataclass(frozen=True)
class EpisodeSettings:
    """A family's own episode settings, where its worlds are not at copi's usual scale
    (CrowdNav's scenarios: a step is 0.25 s, the agent's radius 1.2 steps)."""

    agent_radius: float = 0.3
    goal_tolerance: float = 0.5
    max_range: float = 10.0
    """The ring's range, agent steps."""
    max_steps: int | None = None
    """A fixed step limit (None: three times the optimum and 100, as everywhere)."""
    seconds_per_step: float | None = None
    """Physical time of one step, where the family has physical units."""
    metres_per_step: float | None = None
    discomfort: float | None = None
    """Steps closer to a moving obstacle than this (surface to surface, agent steps)
    count as uncomfortable (CrowdNav's discomfort frequency)."""
    episodes: int | None = None
    """Episodes the benchmark runs of the family unless told (CrowdNav's test set: 500)."""


@dataclass(frozen=True)
class FamilySpec:
    """A registered world family."""

    name: str
    sampler: Sampler
    summary: str = ""
    inputs: Callable[[], dict[str, str]] | None = field(default=None, compare=False)
    """The content hashes of the data the family draws from, by name (None: the seed
    only): part of every run's identity, so that worlds drawn from other data never
    resume into a run."""
    origin: dict[str, str] = field(default_factory=dict, compare=False)
    """Where the sampler comes from, for another package's family: its package and
    version and a hash of its module's code (:func:`copi._plugins.origin_of`); empty for
    copi's own."""
    episode: EpisodeSettings | None = None
    """Its own episode settings, where they are not copi's usual ones."""


_FAMILIES: Registry[FamilySpec] = Registry("family", ENTRY_POINTS, "families")


def register_family(
    name: str,
    sampler: Sampler,
    *,
    summary: str = "",
    inputs: Callable[[], dict[str, str]] | None = None,
    episode: EpisodeSettings | None = None,
    replace: bool = False,
) -> FamilySpec:
    """Register world family ``name``: ``sampler(rng, *, name=None)`` draws a
    :class:`World` from a numpy Generator (every random choice from it), which
    :func:`sample_world` then returns. Episodes of the family draw their task, start and
    obstacles after the world, from the same generator; ``episode``: the family's own
    agent radius, goal tolerance, ring range, step limit and physical units, where they
    are not copi's usual ones.

    Examples
    --------
    >>> def square(rng, *, name=None):
    ...     side = float(rng.uniform(20, 30))
    ...     return World([[0, 0], [side, 0], [side, side], [0, side]], name=name or "square")
    >>> _ = register_family("doc-square", square, summary="an empty square", replace=True)
    >>> sample_world("doc-square", 0).name, "doc-square" in family_names()
    ('square', True)
    >>> unregister_family("doc-square")
    """
    if not callable(sampler):
        raise InvalidArgumentError(f"the sampler of {name} must be callable; got {sampler!r}")
    old = _FAMILIES.current(name)
    same = old is not None and old.sampler is sampler
    spec = FamilySpec(name, sampler, summary, inputs, origin_of(sampler, "family"), episode)
    return _FAMILIES.add(name, spec, same=same, replace=replace)


def unregister_family(name: str) -> None:
    """Remove a registered family (e.g. one a test registered); copi's own stay, and one
    registered over copi's own puts copi's back."""
    _FAMILIES.remove(name)


def family_replaced(name: str) -> bool:
    """Whether ``name``, one of copi's own families, is registered over by another
    package (``register_family(..., replace=True)``)."""
    return _FAMILIES.replaced(name)


def family_names() -> tuple[str, ...]:
    """Every registered family: copi's own (sorted), then those of other packages."""
    return _FAMILIES.names()


def family_spec(family: str) -> FamilySpec:
    """A registered family by name; an unknown name is refused, listing the known ones."""
    spec = _FAMILIES.get(family)
    if spec is None:
        raise InvalidArgumentError(
            f"family must be one of {', '.join(family_names())}; got {family!r}"
            f"{_FAMILIES.unknown(family)}"
        )
    return spec


def check_family(family: str) -> str:
    """``family`` if it names a registered family; otherwise one clear error listing them."""
    family_spec(family)
    return family


def family_inputs(family: str) -> dict[str, str]:
    """The content hashes of the data a family draws its worlds from, by name: part of
    the identity of every run of the family, so that worlds drawn from other data never
    resume into it. ``maps``: ``{"maps_sha": maps_identity()}`` (the map set of
    :func:`movingai_dir`); the generated families draw from nothing but the seed. Another
    package's family adds where it comes from (:attr:`FamilySpec.origin`).

    Examples
    --------
    >>> family_inputs("star"), sorted(family_inputs("maps"))
    ({}, ['maps_sha'])
    """
    spec = family_spec(family)
    origin = spec.origin
    if not origin and _FAMILIES.replaced(family):  # copi's own sampler under another name
        origin = replaced_origin(spec.sampler, "family")
    return {**origin, **({} if spec.inputs is None else dict(spec.inputs()))}


def sample_world(
    family: str,
    seed: Seed = None,
    *,
    name: str | None = None,
    data_dir: str | os.PathLike[str] | None = None,
) -> World:
    """Draw a world of a named family.

    ``star``
        The paper's random worlds, :func:`random_world` (a star-shaped polygon of 4 to 12
        sides, no holes), kept for continuity with earlier results.
    ``polygon``
        :func:`polygon_world`: random simple polygons that are not star-shaped, with thin
        partial walls, alcoves and 0 to 3 convex holes; the goal is in straight sight of
        the start in about a third of the tasks.
    ``indoor``
        :func:`indoor_world`: rooms, doors and corridors on a random floor plan, with
        dead ends and U-shaped detours; the goal is rarely in sight.
    ``maps``
        :func:`map_window_world`: windows of the Moving AI maps in ``data_dir`` (see
        :func:`movingai_dir` for the default), scaled so passages fit the agent and the
        moving obstacles, which are sized to fit them.
    ``crowd``
        The ``polygon`` world of the same seed with 25 to 40 obstacles moving at 0.8
        (:data:`CROWD_OBSTACLES`).

    and any family registered with :func:`register_family`. World k of a family for
    seed s is ``sample_world(family, default_rng([s, k]))``, as episodes elsewhere in
    copi; passing the same generator on to :meth:`Simulator.from_world` then draws the
    task.

    Parameters
    ----------
    family : str
        A registered family (:func:`family_names`).
    seed : int or Generator, optional
    name : str, optional
        The world's name; by default the family and a short description.
    data_dir : path, optional
        Directory of Moving AI maps, used by ``maps`` only.

    Raises
    ------
    InvalidArgumentError
        For an unknown family, or for ``maps`` when the map directory holds no map.

    Examples
    --------
    >>> import numpy as np
    >>> w = sample_world("indoor", np.random.default_rng([0, 1]))
    >>> w.name.startswith("indoor-"), w == sample_world("indoor", np.random.default_rng([0, 1]))
    (True, True)
    >>> try:
    ...     sample_world("castle")
    ... except InvalidArgumentError as err:
    ...     print(err)  # doctest: +ELLIPSIS
    family must be one of crowd, indoor, maps, polygon, star...; got 'castle'
    """
    spec = family_spec(family)
    rng = as_generator(seed)
    if family == "maps" and data_dir is not None:
        params = MapsParams(data_dir=os.fspath(data_dir))
        return map_window_world(rng, params=params, name=name)
    try:
        world = spec.sampler(rng, name=name)
    except (KeyboardInterrupt, CopiError):
        raise
    except BaseException as exc:  # another package's sampler: its error, named as such
        if ctrl_c_behind(exc) is not None:  # numba's SystemError for a Ctrl-C: the user's
            raise
        did = f"called sys.exit({exc.code!r})" if isinstance(exc, SystemExit) else (
            f"raised {type(exc).__name__}" + (f": {exc}" if str(exc) else ""))  # fmt: skip
        raise InvalidArgumentError(f"the sampler of family {family!r} {did}") from None
    if not isinstance(world, World):
        raise InvalidArgumentError(
            f"the sampler of family {family!r} returned a {type(world).__name__}, not a World"
        )
    return world


def _star(rng: np.random.Generator, *, name: str | None = None) -> World:
    w = random_world(rng)
    return w.replace(name=name or f"star-{len(w.boundary)}gon")


def _crowd(rng: np.random.Generator, *, name: str | None = None) -> World:
    w = polygon_world(rng)
    return w.replace(name=name or "crowd" + w.name[len("polygon") :], obstacles=CROWD_OBSTACLES)


def _maps(rng: np.random.Generator, *, name: str | None = None) -> World:
    return map_window_world(rng, name=name)


_CROWDNAV = EpisodeSettings(
    agent_radius=CROWDNAV.radius * STEPS_PER_METRE,
    goal_tolerance=CROWDNAV.radius * STEPS_PER_METRE,
    max_range=CROWDNAV.neighbor_dist * STEPS_PER_METRE,
    max_steps=round((CROWDNAV.time_limit - 1.0) / CROWDNAV.time_step),
    seconds_per_step=CROWDNAV.time_step, metres_per_step=1.0 / STEPS_PER_METRE,
    discomfort=CROWDNAV.discomfort_dist * STEPS_PER_METRE, episodes=500,
)  # fmt: skip
"""CrowdNav's robot in copi's units: radius 0.3 m, success within it of the goal, 10 m
seen, 96 decisions (CrowdNav's timeout comes at 24 s), a step of 0.25 s."""

for _name, _sampler, _summary, _inputs in (
    ("crowd", _crowd, "the polygon worlds with 25-40 obstacles moving at 0.8", None),
    ("indoor", indoor_world, "rooms, doors and corridors on a random floor plan", None),
    ("maps", _maps, "windows of Moving AI grid maps, scaled for disc agents",
     lambda: {"maps_sha": maps_identity()}),
    ("polygon", polygon_world, "random simple polygons, not star-shaped, with holes", None),
    ("star", _star, "the paper's random star-shaped polygons of 4 to 12 sides", None),
):  # fmt: skip
    register_family(_name, _sampler, summary=_summary, inputs=_inputs)
register_family("circle-crossing", circle_crossing, episode=_CROWDNAV,
                summary="CrowdNav's circle crossing: 5 ORCA humans crossing a circle of 4 m, "
                "the robot invisible to them (needs the extra peers)")  # fmt: skip
register_family("square-crossing", square_crossing, episode=_CROWDNAV,
                summary="CrowdNav's square crossing: 5 ORCA humans crossing a 10 m square, the "
                "robot invisible to them (needs the extra peers)")  # fmt: skip
_FAMILIES.seal()


BENCHMARK_FAMILIES = ("star", "polygon", "indoor", "maps", "crowd")
"""copi's five families in the order results show them (the paper's first): what the
benchmark runs unless told otherwise."""


def in_sight(world: World, a: Any, b: Any, *, radius: float = 0.0) -> bool:
    """Whether a disc of ``radius`` can move in a straight line from ``a`` to ``b`` among
    the static walls (the segment lies in the free space, at least ``radius`` from every
    wall).

    Examples
    --------
    >>> from copi.world import World
    >>> u = World([[0, 0], [10, 0], [10, 10], [0, 10]], [[[4, 1], [6, 1], [6, 9], [4, 9]]])
    >>> in_sight(u, [2, 5], [8, 5]), in_sight(u, [2, 0.8], [8, 0.8])
    (False, True)
    >>> in_sight(u, [2, 0.8], [8, 0.8], radius=0.3)  # 0.2 from the hole
    False
    """
    p = as_vector(a, "a", length=2)
    q = as_vector(b, "b", length=2)
    line = LineString([p, q])
    if not shapely.covers(world.polygon, line):
        return False
    return radius <= 0 or float(shapely.distance(line, world.polygon.boundary)) >= radius
