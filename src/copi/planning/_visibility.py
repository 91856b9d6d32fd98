"""Exact Euclidean shortest paths in a closed polygonal free space (visibility graph)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import shapely
import shapely.ops
from numpy.typing import NDArray
from shapely.geometry import MultiPolygon, Polygon
from shapely.geometry.base import BaseGeometry

from copi._validation import FloatArray, as_vector
from copi.errors import InvalidArgumentError, InvalidQueryError, InvalidWorldError
from copi.planning import kernels

MAX_WORK = 2e11
"""Most (corner pair, edge) tests a visibility graph may take to build (corners squared
times vertices; about 40 s on one core at 5e9 a second): a free space beyond it (the
configuration space of a whole 256 x 256 map at one cell a step has 8.7e12) is refused
instead of planned for hours."""

__all__ = ["Plan", "VisibilityGraph", "check_work", "rings_of"]


def rings_of(geometry: BaseGeometry) -> tuple[FloatArray, NDArray[np.int64]]:
    """The rings of a (Multi)Polygon free space as the kernels take them: vertices ``xy``
    (free space on the left) and each ring's first index in ``starts``."""
    polys = [shapely.geometry.polygon.orient(p, 1.0) for p in _polygons(geometry)]
    rings = [np.asarray(r.coords)[:-1] for p in polys for r in (p.exterior, *p.interiors)]
    rings = [r for r in rings if len(r) >= 3]
    xy = np.ascontiguousarray(np.vstack(rings), dtype=np.float64) if rings else np.zeros((0, 2))
    starts = np.concatenate([[0], np.cumsum([len(r) for r in rings])]).astype(np.int64)
    return xy, starts


def check_work(corners: int, vertices: int) -> None:
    """Refuse a free space whose visibility graph would take more than :data:`MAX_WORK`
    tests to build, saying how much it would take and what to do."""
    work = float(corners) ** 2 * vertices
    if work > MAX_WORK:
        raise InvalidWorldError(
            f"the free space has {corners:,} corners on {vertices:,} vertices: its visibility "
            f"graph would test {work:.1e} pairs against edges, more than the planner's "
            f"{MAX_WORK:.0e} (about a minute); give a simpler world (a Moving AI map imported "
            "one cell a step: import it with --passage)"
        )


@dataclass(frozen=True)
class Plan:
    """A planned path: waypoints from start to goal and its Euclidean length.

    When no path exists, ``path`` is None and ``length`` is inf (not an exception:
    "unreachable" is an answer).
    """

    path: FloatArray | None
    """Waypoints of shape (k, 2), start first and goal last; None when unreachable."""
    length: float
    """Sum of the segment lengths, in agent steps (inf when unreachable)."""

    @property
    def found(self) -> bool:
        """Whether a path exists."""
        return self.path is not None


def _polygons(geom: BaseGeometry) -> list[Polygon]:
    if isinstance(geom, Polygon):
        return [] if geom.is_empty else [geom]
    if isinstance(geom, MultiPolygon):
        return [g for g in geom.geoms if not g.is_empty]
    if hasattr(geom, "geoms"):  # a GeometryCollection: keep its areas
        return [g for part in geom.geoms for g in _polygons(part)]
    return []


@dataclass(frozen=True, eq=False)
class VisibilityGraph:
    """The reduced visibility graph of a closed polygonal free space.

    Nodes are the reflex vertices of the free space (where its boundary turns away from
    it, the only places a shortest path can bend); an edge joins two of them when the
    segment between them lies in the closed free space (it may run along edges and touch
    vertices) and is tangent to the boundary at both ends. A query links the start and
    goal to the nodes they see and runs A* with the straight-line heuristic, which gives
    the exact Euclidean shortest path in the polygon.

    Build with :meth:`from_geometry`; one graph answers many queries.

    Examples
    --------
    >>> from shapely.geometry import box
    >>> room = box(0, 0, 10, 10).difference(box(4, 0, 6, 8))
    >>> g = VisibilityGraph.from_geometry(room)
    >>> plan = g.shortest_path([2, 2], [8, 2])
    >>> plan.path.tolist(), round(plan.length, 6)
    ([[2.0, 2.0], [4.0, 8.0], [6.0, 8.0], [8.0, 2.0]], 14.649111)
    """

    geometry: BaseGeometry
    """The free space (Shapely Polygon or MultiPolygon), closed."""
    xy: NDArray[np.float64] = field(repr=False)
    """All boundary vertices, ring after ring, free space on the left of each ring."""
    starts: NDArray[np.int64] = field(repr=False)
    """Ring k is ``xy[starts[k]:starts[k + 1]]``."""
    nodes: NDArray[np.int64] = field(repr=False)
    """Indices into ``xy`` of the reflex vertices (graph nodes)."""
    indptr: NDArray[np.int64] = field(repr=False)
    indices: NDArray[np.int64] = field(repr=False)
    weights: NDArray[np.float64] = field(repr=False)
    eps: float = field(repr=False)
    """Absolute tolerance of the geometric predicates, scaled to the coordinates."""
    pins: NDArray[np.float64] = field(repr=False, default_factory=lambda: np.zeros((0, 2)))
    """Points no path may touch (the pinch points, unless paths may go through them)."""

    @classmethod
    def from_geometry(
        cls, geometry: BaseGeometry, *, through_pinch_points: bool = True
    ) -> VisibilityGraph:
        """Build the graph of a Shapely (Multi)Polygon free space.

        Parameters
        ----------
        geometry : shapely Polygon or MultiPolygon
        through_pinch_points : bool
            Where the free space touches itself at a single point (two parts meeting
            at a vertex, or a hole touching the outer ring), whether a path may pass
            through that point. True is the closed free space of the rest of copi (and
            of extremitypathfinder); False treats such points as walls, as a navigation
            mesh does when faces only share a vertex (the Iron Harvest benchmark).
        """
        if not isinstance(geometry, BaseGeometry):
            raise InvalidArgumentError(
                f"free space must be a Shapely polygon; got {type(geometry).__name__}"
            )
        xy, starts = rings_of(geometry)
        scale = max(1.0, float(np.abs(xy).max())) if len(xy) else 1.0
        eps = 1e-9 * scale
        pins = np.zeros((0, 2))
        if len(xy) and not through_pinch_points:
            # vertices met twice along the rings: where the free space touches itself
            _, first, count = np.unique(xy, axis=0, return_index=True, return_counts=True)
            pins = np.ascontiguousarray(xy[first[count > 1]])
        if len(xy):
            nodes = kernels.reflex_vertices(xy, starts)
            if len(pins):
                pinned = (np.abs(xy[nodes][:, None, :] - pins[None]).max(-1) <= eps).any(1)
                nodes = np.ascontiguousarray(nodes[~pinned])
            check_work(len(nodes), len(xy))
            ei, ej = kernels.visibility_edges(xy, starts, nodes, eps, pins)
        else:
            nodes = np.zeros(0, dtype=np.int64)
            ei = ej = np.zeros(0, dtype=np.int64)
        pts = xy[nodes]
        w = np.hypot(*(pts[ei] - pts[ej]).T)
        # Undirected edges as CSR adjacency over node numbers.
        src = np.concatenate([ei, ej])
        dst = np.concatenate([ej, ei])
        wt = np.concatenate([w, w])
        order = np.argsort(src, kind="stable")
        indptr = np.zeros(len(nodes) + 1, dtype=np.int64)
        np.add.at(indptr, src + 1, 1)
        indptr = np.cumsum(indptr)
        return cls(
            geometry=geometry,
            xy=xy,
            starts=starts,
            nodes=nodes,
            indptr=indptr,
            indices=np.ascontiguousarray(dst[order]),
            weights=np.ascontiguousarray(wt[order]),
            eps=eps,
            pins=pins,
        )

    @property
    def points(self) -> FloatArray:
        """Coordinates of the graph's nodes, shape (n, 2)."""
        return self.xy[self.nodes]

    @property
    def n_edges(self) -> int:
        """Number of (undirected) edges."""
        return int(len(self.indices) // 2)

    def contains(self, point: Any) -> bool:
        """Whether a point lies in the closed free space."""
        p = as_vector(point, "point", length=2)
        return bool(kernels.point_free(p[0], p[1], self.xy, self.starts, self.eps))

    def shortest_path(self, start: Any, goal: Any, *, snap: float = 0.0) -> Plan:
        """The exact shortest path from ``start`` to ``goal``.

        Parameters
        ----------
        start, goal : array_like of shape (2,)
        snap : float
            A start or goal outside the free space but within ``snap`` of it is joined to
            its nearest free point by a first (or last) straight piece. Configuration
            spaces built conservatively use this for points in the thin band between the
            exact and the polygonal boundary.

        Raises
        ------
        InvalidQueryError
            When the start or the goal is not in the closed free space (nor within snap).
        """
        s0 = as_vector(start, "start", length=2)
        g0 = as_vector(goal, "goal", length=2)
        s = self._free_point(s0, "start", snap)
        g = self._free_point(g0, "goal", snap)
        pts = self.points
        xy, st, eps, pins = self.xy, self.starts, self.eps, self.pins
        s_vis = kernels.visible_from(s[0], s[1], xy, st, self.nodes, eps, pins)
        g_vis = kernels.visible_from(g[0], g[1], xy, st, self.nodes, eps, pins)
        direct = bool(kernels.segment_free(s[0], s[1], g[0], g[1], xy, st, eps, pins))
        length, parent = kernels.graph_astar(
            np.ascontiguousarray(pts),
            self.indptr,
            self.indices,
            self.weights,
            s_vis,
            g_vis,
            s[0],
            s[1],
            g[0],
            g[1],
            direct,
        )
        if not math.isfinite(length):
            return Plan(None, math.inf)
        chain = [g] if np.array_equal(g, g0) else [g0, g]
        v = int(parent[len(pts)])
        while v >= 0:
            chain.append(pts[v])
            v = int(parent[v])
        chain.append(s)
        if not np.array_equal(s, s0):
            chain.append(s0)
        path = np.array(chain[::-1])
        extra = float(np.hypot(*(s - s0)) + np.hypot(*(g - g0)))
        return Plan(path, float(length) + extra)

    def _free_point(self, p: FloatArray, name: str, snap: float) -> FloatArray:
        if kernels.point_free(p[0], p[1], self.xy, self.starts, self.eps):
            return p
        where = shapely.points(p)
        gap = float(shapely.distance(self.geometry, where)) if len(self.xy) else math.inf
        if gap <= snap:
            near = shapely.ops.nearest_points(self.geometry, where)[0]
            q = np.array([near.x, near.y])
            if kernels.point_free(q[0], q[1], self.xy, self.starts, self.eps):
                return q
        raise InvalidQueryError(
            f"{name} ({p[0]:.6g}, {p[1]:.6g}) must lie in the free space; "
            + (
                "there is none"
                if not math.isfinite(gap)
                else f"it is inside an obstacle or outside, {gap:.3g} from the nearest free point"
            )
        )
