"""The paper's random worlds (§IV) and random tasks in them."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import shapely
from shapely.geometry import MultiPolygon, Polygon

from copi._rng import Seed, as_generator
from copi._validation import FloatArray
from copi.errors import InvalidArgumentError, InvalidWorldError
from copi.geometry import turned
from copi.geometry.kernels import clearance as _clearance_kernel
from copi.world._world import ObstacleSpec, World

__all__ = [
    "WorldParams",
    "check_task",
    "place_obstacles",
    "random_world",
    "sample_free",
    "sample_start_goal",
]


@dataclass(frozen=True)
class WorldParams:
    """The distribution of :func:`random_world` (paper §IV: "polygons of between four and
    twelve sides, and thus vary considerably in size, shape and convexity").

    A world is a star-shaped polygon around its centre, which makes it simple by
    construction (no rejection loop): vertex k sits at angle ``theta_k`` and radius
    ``R * (1 - c * u_k)``; then the polygon is stretched and rotated.
    """

    sides: tuple[int, int] = (4, 12)
    """Number of sides, uniform on this inclusive range."""
    size: tuple[float, float] = (12.0, 35.0)
    """Circumradius R in agent steps, log-uniform on this range (area spans ~8x)."""
    concavity: tuple[float, float] = (0.0, 0.6)
    """c, uniform on this range: vertex radii are R (1 - c u_k), u_k ~ U(0, 1). c = 0
    gives a convex polygon inscribed in a circle; c = 0.6 deep notches."""
    gap_concentration: float = 3.0
    """Dirichlet concentration of the angular gaps between vertices: larger is more
    regular. Draws with a gap of half a turn or more are redrawn: every edge then spans
    less than half a turn around the centre, which is what makes the polygon simple."""
    elongation: tuple[float, float] = (1.0, 2.0)
    """Aspect ratio e, uniform: x is scaled by sqrt(e) and y by 1/sqrt(e) before a
    uniform random rotation."""

    def __post_init__(self) -> None:
        lo, hi = self.sides
        if not (3 <= lo <= hi):
            raise InvalidArgumentError(f"sides must satisfy 3 <= low <= high; got {self.sides}")
        if not (0 < self.size[0] <= self.size[1]):
            raise InvalidArgumentError(f"size must satisfy 0 < low <= high; got {self.size}")
        if not (0 <= self.concavity[0] <= self.concavity[1] < 1):
            raise InvalidArgumentError(
                f"concavity must satisfy 0 <= low <= high < 1; got {self.concavity}"
            )
        if not (1 <= self.elongation[0] <= self.elongation[1]):
            raise InvalidArgumentError(
                f"elongation must satisfy 1 <= low <= high; got {self.elongation}"
            )
        if not self.gap_concentration > 0:
            raise InvalidArgumentError(
                f"gap_concentration must be > 0; got {self.gap_concentration}"
            )


def random_world(
    seed: Seed = None, *, params: WorldParams | None = None, name: str | None = None
) -> World:
    """Draw one of the paper's random worlds: a polygon of 4 to 12 sides (no holes).

    See :class:`WorldParams` for the distribution. Start, goal and obstacles are left
    unset, to be drawn by the simulator.

    Examples
    --------
    >>> w = random_world(7)
    >>> 4 <= len(w.boundary) <= 12 and w.holes == ()
    True
    >>> random_world(7) == w
    True
    """
    rng = as_generator(seed)
    p = params or WorldParams()
    n = int(rng.integers(p.sides[0], p.sides[1] + 1))
    gaps = rng.dirichlet(np.full(n, p.gap_concentration))
    while gaps.max() >= 0.45:  # < pi with a margin; redraws ~1 in 4 draws at n = 4
        gaps = rng.dirichlet(np.full(n, p.gap_concentration))
    theta = rng.uniform(0, 2 * np.pi) + 2 * np.pi * np.concatenate([[0.0], np.cumsum(gaps[:-1])])
    radius = float(np.exp(rng.uniform(np.log(p.size[0]), np.log(p.size[1]))))
    c = rng.uniform(*p.concavity)
    rho = radius * (1.0 - c * rng.uniform(size=n))
    pts = np.column_stack([rho * np.cos(theta), rho * np.sin(theta)])
    e = rng.uniform(*p.elongation)
    pts *= np.array([np.sqrt(e), 1.0 / np.sqrt(e)])
    phi = rng.uniform(0, 2 * np.pi)
    rot = np.array([[np.cos(phi), -np.sin(phi)], [np.sin(phi), np.cos(phi)]])
    pts = turned(pts, rot)
    pts -= pts.min(axis=0)
    return World(np.round(pts, 6), name=name or f"random-{n}gon")


def _free_component(
    world: World, radius: float, rng: np.random.Generator, containing: FloatArray | None = None
) -> Polygon:
    """A connected component of the free space eroded by ``radius`` (configuration space):
    the one holding ``containing`` if given (or the nearest to it), else one chosen with
    probability proportional to its area."""
    free = world.polygon.buffer(-radius, quad_segs=8)
    parts = list(free.geoms) if isinstance(free, MultiPolygon) else [free]
    parts = [g for g in parts if isinstance(g, Polygon) and g.area > 0]
    if not parts:
        raise InvalidWorldError(
            f"world {world.name!r}: no free space for a disc of radius {radius:g}"
        )
    if containing is not None:
        point = shapely.points(containing)
        return parts[int(np.argmin([g.distance(point) for g in parts]))]
    areas = np.array([g.area for g in parts])
    return parts[int(rng.choice(len(parts), p=areas / areas.sum()))]


def _sample_in(
    region: Polygon,
    segments: FloatArray,
    clearance: float,
    rng: np.random.Generator,
    n: int,
    *,
    tries: int = 50,
) -> FloatArray:
    """Up to ``n`` points uniform in ``region`` at distance >= ``clearance`` from walls."""
    xmin, ymin, xmax, ymax = region.bounds
    found: list[FloatArray] = []
    total = 0
    batch = max(16, 2 * n)
    for _ in range(tries):
        pts = rng.uniform([xmin, ymin], [xmax, ymax], size=(batch, 2))
        pts = pts[shapely.contains_xy(region, pts[:, 0], pts[:, 1])]
        if len(pts):
            d = np.empty(len(pts))
            _clearance_kernel(np.ascontiguousarray(pts), segments, d)
            pts = pts[d >= clearance]
        found.append(pts)
        total += len(pts)
        if total >= n:
            break
    return np.concatenate(found)[:n] if found else np.zeros((0, 2))


def sample_free(world: World, seed: Seed, clearance: float) -> FloatArray:
    """One point uniform in the free space, at least ``clearance`` from every wall (a
    crowd disc's next goal); one clear error when there is none."""
    rng = as_generator(seed)
    got = _sample_in(world.polygon, world.segments, clearance, rng, 1)
    if not len(got):
        raise InvalidWorldError(f"world {world.name!r}: no room for a goal {clearance:g} from "
                                "every wall")  # fmt: skip
    return np.asarray(got[0], dtype=np.float64)


def sample_start_goal(
    world: World,
    seed: Seed = None,
    *,
    radius: float = 0.3,
    min_distance: float = 10.0,
) -> tuple[FloatArray, FloatArray]:
    """Draw a start and a goal for a disc agent of ``radius``: both free, connected, and at
    least ``min_distance`` apart (straight-line), unless the world fixes them.

    Both points lie in the same connected component of the free space eroded by the agent
    radius, so a path exists among the static walls. When the component is too small for
    ``min_distance``, the farthest pair found is refused with an error.

    Examples
    --------
    >>> w = random_world(1)
    >>> s, g = sample_start_goal(w, 1)
    >>> bool(np.hypot(*(s - g)) >= 10.0 and w.contains([s, g]).all())
    True
    """
    rng = as_generator(seed)
    if world.start is not None and world.goal is not None:
        return world.start.copy(), world.goal.copy()
    fixed = world.start if world.start is not None else world.goal
    region = _free_component(world, radius, rng, containing=fixed)
    margin = radius + 1e-6
    for _ in range(20):
        cand = _sample_in(region, world.segments, margin, rng, 64)
        if len(cand) < 2:
            continue
        first = fixed.copy() if fixed is not None else cand[0]
        d = np.hypot(*(cand - first).T)
        ok = np.flatnonzero(d >= min_distance)
        if len(ok):
            other = cand[ok[0]]
            if world.goal is not None:
                return other, first
            return first, other
    raise InvalidWorldError(
        f"world {world.name!r}: found no free start and goal {min_distance:g} apart "
        f"for an agent of radius {radius:g}"
    )


def check_task(world: World, *, radius: float = 0.3, min_distance: float = 10.0) -> None:
    """Refuse a world in which :func:`sample_start_goal` can never find a task: no two
    free points ``min_distance`` apart in one connected component of the free space
    eroded by ``radius`` (or none that far from the world's fixed start or goal).

    Raises
    ------
    InvalidWorldError
        Naming the world and the largest distance its free space offers.

    Examples
    --------
    >>> check_task(random_world(1))
    >>> check_task(World([[0, 0], [4, 0], [4, 4], [0, 4]], name="box"))  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    copi.errors.InvalidWorldError: world 'box': no free start and goal 10 apart ... 4.8 at most)
    """
    if world.start is not None and world.goal is not None:
        return
    free = world.polygon.buffer(-radius, quad_segs=8)
    parts = list(free.geoms) if isinstance(free, MultiPolygon) else [free]
    parts = [g for g in parts if isinstance(g, Polygon) and g.area > 0]
    if not parts:
        raise InvalidWorldError(
            f"world {world.name!r}: no free space for a disc of radius {radius:g}"
        )
    fixed = world.start if world.start is not None else world.goal
    if fixed is not None:
        point = shapely.points(fixed)
        part = parts[int(np.argmin([g.distance(point) for g in parts]))]
        xy = np.asarray(part.exterior.coords)
        span = float(np.hypot(*(xy - fixed).T).max())
    else:
        span = 0.0
        for part in parts:
            xy = np.asarray(part.convex_hull.exterior.coords)
            span = max(span, float(np.hypot(*(xy[:, None] - xy[None]).transpose(2, 0, 1)).max()))
    if span < min_distance:
        raise InvalidWorldError(
            f"world {world.name!r}: no free start and goal {min_distance:g} apart for an "
            f"agent of radius {radius:g} (its free space spans {span:.2g} at most)"
        )


def place_obstacles(
    world: World,
    seed: Seed = None,
    *,
    spec: ObstacleSpec | None = None,
    keep_clear: FloatArray | None = None,
    keep_clear_radius: float = 0.0,
) -> tuple[FloatArray, FloatArray]:
    """Draw the moving obstacles' discs: count and radii from ``spec`` (the world's, else
    the paper's), centres uniform in the free space, never touching a wall, and farther
    than ``keep_clear_radius`` + their radius from each point of ``keep_clear`` (e.g. the
    agent's start, so that no episode begins in contact).

    Returns
    -------
    centers : ndarray of shape (d, 2)
    radii : ndarray of shape (d,)
    """
    rng = as_generator(seed)
    spec = spec or world.obstacles or ObstacleSpec()
    count = int(rng.integers(spec.count[0], spec.count[1] + 1))
    radii = rng.uniform(spec.radius[0], spec.radius[1], size=count)
    centers = np.zeros((count, 2))
    keep = np.zeros((0, 2)) if keep_clear is None else np.atleast_2d(keep_clear)
    for k in range(count):
        region = world.polygon
        placed = False
        for _ in range(20):
            cand = _sample_in(region, world.segments, radii[k] + 1e-6, rng, 16)
            if len(keep):
                far = np.min(np.hypot(*(cand[:, None, :] - keep[None]).transpose(2, 0, 1)), axis=1)
                cand = cand[far > keep_clear_radius + radii[k]]
            if len(cand):
                centers[k] = cand[0]
                placed = True
                break
        if not placed:
            raise InvalidWorldError(
                f"world {world.name!r}: no room for an obstacle of radius {radii[k]:.3g}"
            )
    return centers, radii
