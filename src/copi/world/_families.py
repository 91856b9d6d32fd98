"""World families of the benchmark, each drawn from a seed and reachable by name."""

from __future__ import annotations

import os
from typing import Any

import shapely
from shapely.geometry import LineString

from copi._rng import Seed, as_generator
from copi.errors import InvalidArgumentError
from copi.geometry._arrays import as_vector
from copi.world._family_indoor import indoor_world
from copi.world._family_maps import MapsParams, map_window_world, maps_identity
from copi.world._family_polygon import polygon_world
from copi.world._generate import random_world
from copi.world._world import ObstacleSpec, World

__all__ = [
    "CROWD_OBSTACLES",
    "FAMILIES",
    "check_family",
    "family_inputs",
    "in_sight",
    "sample_world",
]

FAMILIES = ("crowd", "indoor", "maps", "polygon", "star")
"""Names of the world families, sorted (see :func:`sample_world`)."""

CROWD_OBSTACLES = ObstacleSpec(count=(25, 40), radius=(0.5, 1.0), speed=0.8)
"""Moving obstacles of the ``crowd`` family: denser and faster than the paper's."""


def check_family(family: str) -> str:
    """``family`` if it names a family; otherwise one clear error listing them."""
    if family not in FAMILIES:
        raise InvalidArgumentError(f"family must be one of {', '.join(FAMILIES)}; got {family!r}")
    return family


def family_inputs(family: str) -> dict[str, str]:
    """The content hashes of the data a family draws its worlds from, by name: part of
    the identity of every run of the family, so that worlds drawn from other data never
    resume into it. ``maps``: ``{"maps_sha": maps_identity()}`` (the map set of
    :func:`movingai_dir`); the generated families draw from nothing but the seed.

    Examples
    --------
    >>> family_inputs("star"), sorted(family_inputs("maps"))
    ({}, ['maps_sha'])
    """
    check_family(family)
    return {"maps_sha": maps_identity()} if family == "maps" else {}


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

    World k of a family for seed s is ``sample_world(family, default_rng([s, k]))``, as
    episodes elsewhere in copi; passing the same generator on to
    :meth:`Simulator.from_world` then draws the task.

    Parameters
    ----------
    family : str
        One of :data:`FAMILIES`.
    seed : int or Generator, optional
    name : str, optional
        The world's name; by default the family and a short description.
    data_dir : path, optional
        Directory of Moving AI maps, used by ``maps`` only.

    Raises
    ------
    InvalidArgumentError
        For an unknown family, or for ``maps`` when no map directory is found.

    Examples
    --------
    >>> import numpy as np
    >>> w = sample_world("indoor", np.random.default_rng([0, 1]))
    >>> w.name.startswith("indoor-"), w == sample_world("indoor", np.random.default_rng([0, 1]))
    (True, True)
    >>> try:
    ...     sample_world("castle")
    ... except InvalidArgumentError as err:
    ...     print(err)
    family must be one of crowd, indoor, maps, polygon, star; got 'castle'
    """
    check_family(family)
    rng = as_generator(seed)
    if family == "star":
        w = random_world(rng)
        return w.replace(name=name or f"star-{len(w.boundary)}gon")
    if family == "polygon":
        return polygon_world(rng, name=name)
    if family == "crowd":
        w = polygon_world(rng)
        return w.replace(name=name or "crowd" + w.name[len("polygon") :], obstacles=CROWD_OBSTACLES)
    if family == "indoor":
        return indoor_world(rng, name=name)
    params = MapsParams(data_dir=None if data_dir is None else os.fspath(data_dir))
    return map_window_world(rng, params=params, name=name)


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
