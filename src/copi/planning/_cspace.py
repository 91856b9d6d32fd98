"""Configuration space of a disc agent, and shortest paths in it."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import shapely
from shapely.geometry.base import BaseGeometry

from copi._validation import FloatArray, as_discs, as_vector
from copi.errors import InvalidArgumentError, InvalidQueryError, InvalidWorldError
from copi.geometry.kernels import clearance as _clearance_kernel
from copi.planning import kernels
from copi.planning._visibility import Plan, VisibilityGraph, check_work, rings_of
from copi.world import World

__all__ = ["configuration_space", "length_error_bound", "shortest_path"]


def length_error_bound(quad_segs: int = 16) -> float:
    """Relative length error of :func:`shortest_path` for an agent with radius > 0 or
    with disc obstacles: 1 / cos(pi / (4 quad_segs)) - 1 (0.12 % for 16).

    Each circle of the configuration space (a disc obstacle grown by the agent radius, or
    the rounded corner of a grown wall) is replaced by the polygon of 4 quad_segs sides
    circumscribed about it, so the planned path is feasible for the true disc agent and at
    least as long as the true optimum. The same polygons inscribed give a path no longer
    than the optimum; the circumscribed polygon is the inscribed one scaled by
    1 / cos(pi / (4 quad_segs)), which bounds the ratio of the two lengths *when both
    spaces have the same passages*. A gap between two grown discs that is open in the true
    space but closed by the circumscribed polygons sends the path another way round,
    which may be longer by more (the tests found 8.8 % against 8.2 % for quad_segs 2);
    the test suite checks the bracket on random snapshots (``tests/planning/test_cspace.py``).

    Examples
    --------
    >>> round(length_error_bound(16), 6)
    0.001206
    """
    return 1.0 / math.cos(math.pi / (4 * quad_segs)) - 1.0


def _walls(space: World | BaseGeometry) -> tuple[BaseGeometry, FloatArray]:
    if isinstance(space, World):
        return space.polygon, np.asarray(space.segments)
    if isinstance(space, BaseGeometry):
        rings = shapely.get_rings(shapely.get_parts(space))
        segs = [
            np.hstack([c[:-1], c[1:]]) for c in (np.asarray(r.coords) for r in rings) if len(c) > 1
        ]
        return space, np.vstack(segs) if segs else np.zeros((0, 4))
    raise InvalidArgumentError(
        f"space must be a World or a Shapely polygon; got {type(space).__name__}"
    )


def configuration_space(
    space: World | BaseGeometry,
    *,
    radius: float = 0.0,
    centers: Any = None,
    radii: Any = None,
    quad_segs: int = 16,
    conservative: bool = True,
) -> BaseGeometry:
    """The free space of a disc agent's centre: walls and holes grown by ``radius``, disc
    obstacles by ``radius`` + their own radius (a frozen snapshot of moving obstacles).

    Circles are polygons of 4 ``quad_segs`` sides, circumscribed when ``conservative``
    (the default: every point of the result is truly free) and inscribed otherwise (the
    result contains the true free space; used to bound the error). With radius 0 and no
    discs the result is the space itself, exactly.

    Returns
    -------
    shapely Polygon or MultiPolygon
    """
    free, segs = _walls(space)
    r = float(radius)
    if not (math.isfinite(r) and r >= 0):
        raise InvalidArgumentError(f"radius must be a finite number >= 0; got {radius!r}")
    if int(quad_segs) != quad_segs or quad_segs < 1:
        raise InvalidArgumentError(f"quad_segs must be a positive int; got {quad_segs!r}")
    c, rr = as_discs(centers, radii)
    scale = 1.0 / math.cos(math.pi / (4 * quad_segs)) if conservative else 1.0
    angles = np.arange(4 * quad_segs) * (2 * math.pi / (4 * quad_segs))
    unit = np.column_stack([np.cos(angles), np.sin(angles)])
    parts = []
    if r > 0 and len(segs):
        ring = unit * (r * scale)
        corners = np.concatenate(
            [segs[:, None, :2] + ring[None], segs[:, None, 2:] + ring[None]], axis=1
        )
        parts.append(shapely.convex_hull(shapely.multipoints(corners)))
    if len(c):
        grown = (rr + r) * scale
        parts.append(shapely.polygons(c[:, None, :] + grown[:, None, None] * unit[None]))
    if not parts:
        return free
    blocked = shapely.union_all(np.concatenate(parts))
    return shapely.difference(free, blocked)


MAX_PLANNED_VERTICES = 20_000
"""Most vertices (boundary and holes) of a world that episodes are run in: growing its
walls by the agent's radius alone takes about half a millisecond a vertex (10 s at this
cap, a minute at 70,000), before any plan. The largest Moving AI map copi ships, scaled
for agents, has 2,300."""


def check_size(world: World) -> None:
    """Refuse, in one line, a world of more than :data:`MAX_PLANNED_VERTICES` vertices."""
    n = len(world.boundary) + sum(len(h) for h in world.holes)
    if n > MAX_PLANNED_VERTICES:
        raise InvalidWorldError(
            f"world {world.name!r} has {n:,} vertices, more than episodes are planned in (at "
            f"most {MAX_PLANNED_VERTICES:,}: growing its walls by the agent's radius alone "
            "would take minutes); simplify it, or import its map with a larger --passage"
        )


def check_plannable(space: World | BaseGeometry, *, radius: float = 0.0) -> None:
    """Refuse, in one line, a world whose configuration space for an agent of ``radius``
    is too fine for the exact planner (:func:`~copi.planning._visibility.check_work`), or
    of more than :data:`MAX_PLANNED_VERTICES` vertices: before a run, rather than at its
    first episode."""
    if isinstance(space, World):
        check_size(space)
    xy, starts = rings_of(configuration_space(space, radius=radius))
    if len(xy):
        check_work(len(kernels.reflex_vertices(xy, starts)), len(xy))


def shortest_path(
    space: World | BaseGeometry,
    start: Any,
    goal: Any,
    *,
    radius: float = 0.0,
    centers: Any = None,
    radii: Any = None,
    quad_segs: int = 16,
) -> Plan:
    """Shortest path of a disc agent of ``radius`` from ``start`` to ``goal`` among the
    walls of ``space`` and the frozen discs (``centers``, ``radii``).

    Exact (to rounding) for a point agent among polygons; otherwise feasible for the true
    disc agent and within :func:`length_error_bound` of the optimum (the paper's reference,
    §IV: "an optimal A* shortest path, run on stationary snapshots of the environment").

    Raises
    ------
    InvalidQueryError
        When the start or goal is not free for the agent, saying how far it is from free.

    Examples
    --------
    >>> w = World([[0, 0], [10, 0], [10, 10], [0, 10]], [[[4, 0.5], [6, 0.5], [6, 8], [4, 8]]])
    >>> shortest_path(w, [2, 2], [8, 2]).length  # a point slips under the wall
    7.0
    >>> round(shortest_path(w, [2, 2], [8, 2], radius=0.3).length, 2)  # a disc goes over
    15.41
    """
    s = as_vector(start, "start", length=2)
    g = as_vector(goal, "goal", length=2)
    c, rr = as_discs(centers, radii)
    free, segs = _walls(space)
    for name, p in (("start", s), ("goal", g)):
        _check_free(name, p, free, segs, radius, c, rr)
    cspace = configuration_space(space, radius=radius, centers=c, radii=rr, quad_segs=quad_segs)
    graph = VisibilityGraph.from_geometry(cspace)
    band = (radius + (float(rr.max()) if len(rr) else 0.0)) * length_error_bound(quad_segs)
    return graph.shortest_path(s, g, snap=band + 1e-9)


def _check_free(
    name: str,
    p: FloatArray,
    free: BaseGeometry,
    segs: FloatArray,
    radius: float,
    centers: FloatArray,
    radii: FloatArray,
) -> None:
    """Refuse a point that is not free for the true disc agent, saying why."""
    tol = 1e-9 * max(1.0, float(np.abs(p).max()))
    if not shapely.intersects_xy(free, p[0], p[1]):
        gap = float(shapely.distance(free, shapely.points(p)))
        raise InvalidQueryError(
            f"{name} ({p[0]:.6g}, {p[1]:.6g}) must lie in the free space; "
            f"it is inside an obstacle or outside, {gap:.3g} from the nearest free point"
        )
    if radius > 0 and len(segs):
        d = np.empty(1)
        _clearance_kernel(p[None], np.ascontiguousarray(segs), d)
        if d[0] < radius - tol:
            raise InvalidQueryError(
                f"{name} ({p[0]:.6g}, {p[1]:.6g}) is {d[0]:.3g} from a wall; an agent of "
                f"radius {radius:g} needs at least {radius:g}"
            )
    if len(centers):
        gaps = np.hypot(*(centers - p).T) - radii - radius
        k = int(np.argmin(gaps))
        if gaps[k] < -tol:
            raise InvalidQueryError(
                f"{name} ({p[0]:.6g}, {p[1]:.6g}) overlaps obstacle {k} (disc at "
                f"({centers[k, 0]:.6g}, {centers[k, 1]:.6g}), radius {radii[k]:g})"
            )
