"""The ``polygon`` world family: random simple polygons that are not star-shaped, with holes."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import shapely
from shapely.geometry import LineString, Polygon

from copi._rng import Seed, as_generator
from copi._validation import FloatArray
from copi.errors import InvalidArgumentError, InvalidWorldError
from copi.geometry import signed_area, turned
from copi.world._world import World

__all__ = ["PolygonParams", "is_star_shaped", "polygon_world"]


@dataclass(frozen=True)
class PolygonParams:
    """The distribution of :func:`polygon_world`: the paper's "polygons of between four and
    twelve sides, [varying] considerably in size, shape and convexity" (§IV) read generally.

    A world starts as ``sides`` random points untangled into a simple polygon (2-opt: while
    two edges cross, reverse the chain between them), stretched and rotated. Thin *notches*
    (partial walls pushed in from an edge) and rectangular *spurs* (alcoves pushed out of an
    edge) are added, and more notches until the boundary is not star-shaped. Last come
    convex polygonal holes. Every passage left by a notch or a hole is at least ``gap``
    wide, so agents and obstacles can get around it.
    """

    sides: tuple[int, int] = (4, 12)
    """Number of random vertices of the base polygon, uniform on this inclusive range."""
    size: tuple[float, float] = (14.0, 35.0)
    """Radius of the disc the vertices are drawn in, in agent steps, log-uniform."""
    elongation: tuple[float, float] = (1.0, 2.0)
    """Aspect ratio, uniform: x is scaled by its square root and y by its inverse."""
    notches: tuple[int, int] = (1, 3)
    """Number of partial walls pushed in from the boundary, uniform inclusive."""
    spurs: tuple[int, int] = (0, 2)
    """Number of alcoves pushed out of the boundary, uniform inclusive."""
    holes: tuple[int, int] = (0, 3)
    """Number of polygonal holes, uniform inclusive."""
    hole_size: tuple[float, float] = (0.08, 0.25)
    """Hole radius as a fraction of the size, uniform."""
    min_angle: float = 25.0
    """Convex corners of the base polygon sharper than this, in degrees, are cut off (a
    spike no agent can enter is no part of the task)."""
    gap: float = 2.5
    """Least width, in agent steps, of a passage beside a notch or a hole."""
    agent_radius: float = 0.3
    """Worlds whose free space falls apart for an agent of this radius are redrawn, so
    that start, goal and obstacles always share one connected space."""

    def __post_init__(self) -> None:
        for key in ("sides", "notches", "spurs", "holes"):
            lo, hi = getattr(self, key)
            if not (0 <= lo <= hi):
                raise InvalidArgumentError(
                    f"{key} must satisfy 0 <= low <= high; got {getattr(self, key)}"
                )
        if self.sides[0] < 4:
            raise InvalidArgumentError(f"sides must be >= 4; got {self.sides}")
        for key in ("size", "hole_size"):
            lo, hi = getattr(self, key)
            if not (0 < lo <= hi):
                raise InvalidArgumentError(
                    f"{key} must satisfy 0 < low <= high; got {getattr(self, key)}"
                )
        if not (1 <= self.elongation[0] <= self.elongation[1]):
            raise InvalidArgumentError(
                f"elongation must satisfy 1 <= low <= high; got {self.elongation}"
            )
        if not self.gap > 0:
            raise InvalidArgumentError(f"gap must be > 0; got {self.gap}")
        if not self.agent_radius >= 0:
            raise InvalidArgumentError(f"agent_radius must be >= 0; got {self.agent_radius}")


def _crossings(pts: FloatArray) -> list[tuple[int, int]]:
    """Pairs (i, j), i < j, of non-adjacent edges of the closed chain ``pts`` that cross."""
    n = len(pts)
    a, b = pts, np.roll(pts, -1, axis=0)
    i, j = np.triu_indices(n, 2)
    keep = ~((i == 0) & (j == n - 1))
    i, j = i[keep], j[keep]

    def orient(p: FloatArray, q: FloatArray, r: FloatArray) -> FloatArray:
        u, v = q - p, r - p
        return np.sign(u[:, 0] * v[:, 1] - u[:, 1] * v[:, 0])

    hit = (orient(a[i], b[i], a[j]) != orient(a[i], b[i], b[j])) & (
        orient(a[j], b[j], a[i]) != orient(a[j], b[j], b[i])
    )
    return list(zip(i[hit].tolist(), j[hit].tolist(), strict=True))


def _is_ccw(ring: FloatArray) -> bool:
    return signed_area(ring) > 0


def _untangle(pts: FloatArray, rng: np.random.Generator) -> FloatArray:
    """A simple polygon through all of ``pts`` (2-opt moves until no two edges cross; each
    move shortens the tour, so this ends)."""
    pts = pts.copy()
    while True:
        pairs = _crossings(pts)
        if not pairs:
            return pts
        i, j = pairs[int(rng.integers(len(pairs)))]
        pts[i + 1 : j + 1] = pts[i + 1 : j + 1][::-1].copy()


def _blunt(ring: FloatArray, min_angle: float) -> FloatArray | None:
    """``ring`` without its spikes: convex vertices sharper than ``min_angle`` (degrees) are
    cut off, sharpest first; None when fewer than 4 vertices remain or a cut would make
    the polygon non-simple."""
    ring = ring.copy()
    while len(ring) >= 4:
        prev, nxt = np.roll(ring, 1, axis=0) - ring, np.roll(ring, -1, axis=0) - ring
        cos = (prev * nxt).sum(axis=1) / (np.hypot(*prev.T) * np.hypot(*nxt.T))
        angle = np.degrees(np.arccos(np.clip(cos, -1.0, 1.0)))
        # only convex vertices are spikes; a reflex vertex's inner angle is 360 - angle
        cross = prev[:, 0] * nxt[:, 1] - prev[:, 1] * nxt[:, 0]
        convex = (cross < 0) if _is_ccw(ring) else (cross > 0)
        angle = np.where(convex, angle, 360.0)
        k = int(np.argmin(angle))
        if angle[k] >= min_angle:
            return ring if len(ring) >= 4 and not _crossings(ring) else None
        ring = np.delete(ring, k, axis=0)
    return None


def is_star_shaped(ring: FloatArray) -> bool:
    """Whether a simple polygon has a point that sees all of it (a non-empty kernel: the
    intersection of the inner half-planes of its edges).

    Examples
    --------
    >>> ell = [[0, 0], [6, 0], [6, 2], [2, 2], [2, 6], [0, 6]]
    >>> is_star_shaped(np.array(ell, dtype=float))  # seen whole from its corner (1, 1)
    True
    >>> u = [[0, 0], [6, 0], [6, 6], [4, 6], [4, 2], [2, 2], [2, 6], [0, 6]]
    >>> is_star_shaped(np.array(u, dtype=float))  # no point sees both tops of the U
    False
    """
    ring = np.asarray(ring, dtype=np.float64)
    p = ring if _is_ccw(ring) else ring[::-1]
    q = np.roll(p, -1, axis=0)
    span = 4.0 * float(np.ptp(ring, axis=0).max()) + 1.0
    kernel: shapely.Geometry = Polygon(ring)
    for a, b in zip(p, q, strict=True):
        d = (b - a) / np.hypot(*(b - a))
        left = np.array([-d[1], d[0]])
        far, side = span * d, span * left
        half = Polygon([a - far, a + far, a + far + side, a - far + side])
        kernel = shapely.intersection(kernel, half)
        if kernel.is_empty or kernel.area <= 1e-12:
            return False
    return True


def _inner_depth(poly: Polygon, origin: FloatArray, direction: FloatArray, reach: float) -> float:
    """Distance from ``origin`` (on the boundary) along ``direction`` to the next wall."""
    ray = LineString([origin + 1e-6 * direction, origin + reach * direction])
    hit = shapely.intersection(ray, poly.boundary)
    if hit.is_empty:
        return reach
    pts = shapely.get_coordinates(hit)
    return float(np.min(np.hypot(*(pts - origin).T)))


def _edit(
    ring: FloatArray, rng: np.random.Generator, gap: float, *, outward: bool
) -> FloatArray | None:
    """``ring`` (counter-clockwise) with a notch (a thin wall pushed in) or a spur (an
    alcove pushed out) on a random edge; None when the drawn one does not fit."""
    n = len(ring)
    k = int(rng.integers(n))
    a, b = ring[k], ring[(k + 1) % n]
    length = float(np.hypot(*(b - a)))
    width = rng.uniform(0.6, 1.5) if not outward else rng.uniform(gap, max(gap, 0.6 * length))
    if length < width + 2.0:
        return None
    d = (b - a) / length
    inward = np.array([-d[1], d[0]])  # left of a counter-clockwise edge
    t = rng.uniform(1.0, length - width - 1.0)
    m1, m2 = a + t * d, a + (t + width) * d
    poly = Polygon(ring)
    reach = 4.0 * float(np.ptp(ring, axis=0).max())
    if outward:
        depth = rng.uniform(gap, max(gap, 0.5 * length))
        new = [m1, m1 - depth * inward, m2 - depth * inward, m2]
    else:
        room = _inner_depth(poly, a + (t + width / 2) * d, inward, reach)
        if room < 2 * gap + 1.0:
            return None
        depth = rng.uniform(0.35, 0.75) * room
        depth = min(depth, room - gap)
        new = [m1, m1 + depth * inward, m2 + depth * inward, m2]
    out = np.vstack([ring[: k + 1], np.array(new), ring[k + 1 :]])
    cand = Polygon(out)
    if not cand.is_valid or not cand.exterior.is_simple:
        return None
    if not isinstance(cand.buffer(-gap / 2), Polygon):  # it closed off a passage
        return None
    if not outward:
        # the wall's tip must leave a passage of at least gap to every other wall
        tip = LineString([new[1], new[2]])
        others = shapely.difference(cand.boundary, LineString(new).buffer(1e-6))
        if shapely.distance(tip, others) < gap:
            return None
    else:
        rest = shapely.difference(poly.boundary, LineString([a, b]).buffer(1e-6))
        if shapely.distance(Polygon(new), rest) < gap:
            return None
    return out


def _hole(
    poly: Polygon, holes: list[Polygon], rng: np.random.Generator, radius: float, gap: float
) -> Polygon | None:
    """A random convex polygon of ``radius`` that keeps ``gap`` from walls and holes."""
    room = poly.buffer(-(gap + radius))
    for h in holes:
        room = room.difference(h.buffer(gap + radius))
    if room.is_empty or room.area <= 0:
        return None
    xmin, ymin, xmax, ymax = room.bounds
    for _ in range(50):
        c = rng.uniform([xmin, ymin], [xmax, ymax])
        if shapely.contains_xy(room, c[0], c[1]):
            break
    else:
        return None
    m = int(rng.integers(3, 8))
    theta = np.sort(rng.uniform(0, 2 * np.pi, m))
    rho = radius * rng.uniform(0.5, 1.0, m)
    pts = c + np.column_stack([rho * np.cos(theta), rho * np.sin(theta)])
    hull = shapely.convex_hull(shapely.multipoints(pts))
    if not isinstance(hull, Polygon) or hull.area < 0.25 * radius**2:
        return None
    return hull


def _base_ring(rng: np.random.Generator, p: PolygonParams, radius: float) -> FloatArray | None:
    """Random points untangled into a counter-clockwise simple polygon without spikes or
    narrow necks; None to redraw."""
    n = int(rng.integers(p.sides[0], p.sides[1] + 1))
    r = radius * np.sqrt(rng.uniform(0.05, 1.0, n))
    theta = rng.uniform(0, 2 * np.pi, n)
    pts = np.column_stack([r * np.cos(theta), r * np.sin(theta)])
    e = rng.uniform(*p.elongation)
    pts *= np.array([np.sqrt(e), 1.0 / np.sqrt(e)])
    ring = _blunt(_untangle(pts, rng), p.min_angle)
    if ring is None:
        return None
    poly = Polygon(ring)
    # narrow necks of the untangled chain would split the world; redraw those
    core = poly.buffer(-p.gap / 2)
    if not isinstance(core, Polygon) or core.area < 0.5 * poly.area:
        return None
    return ring if _is_ccw(ring) else ring[::-1].copy()


def _edited(ring: FloatArray, rng: np.random.Generator, p: PolygonParams) -> FloatArray | None:
    """``ring`` with its notches and spurs, then more notches until it is not star-shaped;
    None to redraw."""
    edits = ["notch"] * int(rng.integers(p.notches[0], p.notches[1] + 1))
    edits += ["spur"] * int(rng.integers(p.spurs[0], p.spurs[1] + 1))
    rng.shuffle(edits)
    for kind in edits:
        for _ in range(10):
            out = _edit(ring, rng, p.gap, outward=kind == "spur")
            if out is not None:
                ring = out
                break
    for _ in range(50):
        if not is_star_shaped(ring):
            return ring
        out = _edit(ring, rng, p.gap, outward=False)
        if out is not None:
            ring = out
    return None


def polygon_world(
    seed: Seed = None, *, params: PolygonParams | None = None, name: str | None = None
) -> World:
    """Draw a world of the ``polygon`` family (see :class:`PolygonParams`): a simple polygon
    whose boundary is not star-shaped, with 0 to 3 convex holes.

    Examples
    --------
    >>> w = polygon_world(3)
    >>> is_star_shaped(w.boundary), w == polygon_world(3)
    (False, True)
    """
    rng = as_generator(seed)
    p = params or PolygonParams()
    for _ in range(1000):
        world = _draw(rng, p, name)
        if world is not None:
            return world
    raise InvalidWorldError(f"no polygon world in 1000 draws from {p}")


def _draw(rng: np.random.Generator, p: PolygonParams, name: str | None) -> World | None:
    radius = float(np.exp(rng.uniform(np.log(p.size[0]), np.log(p.size[1]))))
    base = _base_ring(rng, p, radius)
    ring = None if base is None else _edited(base, rng, p)
    if ring is None:
        return None
    poly = Polygon(ring)
    holes: list[Polygon] = []
    for _ in range(int(rng.integers(p.holes[0], p.holes[1] + 1))):
        size = radius * rng.uniform(*p.hole_size)
        for _ in range(3):  # a smaller hole where the drawn one finds no room
            h = _hole(poly, holes, rng, size, p.gap)
            if h is not None:
                holes.append(h)
                break
            size *= 0.6
    phi = rng.uniform(0, 2 * np.pi)
    rot = np.array([[np.cos(phi), -np.sin(phi)], [np.sin(phi), np.cos(phi)]])
    shift = turned(ring, rot).min(axis=0)
    boundary = np.round(turned(ring, rot) - shift, 6)
    hole_rings = tuple(
        np.round(turned(np.asarray(h.exterior.coords)[:-1], rot) - shift, 6) for h in holes
    )
    label = name or f"polygon-{len(boundary)}gon-{len(holes)}holes"
    world = World(boundary, hole_rings, name=label)
    # the simulator draws start and goal in one piece of this (same erosion)
    if not isinstance(world.polygon.buffer(-p.agent_radius, quad_segs=8), Polygon):
        return None
    return world
