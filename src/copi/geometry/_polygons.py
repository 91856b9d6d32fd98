"""Polygon rings: validation, orientation, edges and self-crossings."""

from __future__ import annotations

from typing import Any

import numpy as np

from copi._validation import FloatArray, as_points
from copi.errors import InvalidArgumentError

__all__ = ["as_ring", "orient", "ring_crossings", "ring_segments", "signed_area", "turned"]


def as_ring(coords: Any, name: str = "ring") -> FloatArray:
    """Vertices of a closed polygon ring as an (n, 2) float array.

    A closing vertex equal to the first and repeated consecutive vertices are dropped; at
    least three distinct vertices must remain.

    Examples
    --------
    >>> as_ring([[0, 0], [1, 0], [1, 1], [0, 0]]).tolist()
    [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]]
    """
    pts, _ = as_points(coords, name, allow_single=False)
    keep = np.any(pts != np.roll(pts, -1, axis=0), axis=1)
    if not keep.any():
        keep[0] = True
    pts = pts[keep]
    if pts.shape[0] < 3:
        raise InvalidArgumentError(
            f"{name} must have at least 3 distinct vertices; got {pts.shape[0]}"
        )
    return np.ascontiguousarray(pts)


def signed_area(ring: FloatArray) -> float:
    """Shoelace area: positive for a counter-clockwise ring.

    Examples
    --------
    >>> signed_area([[0, 0], [2, 0], [2, 1], [0, 1]])
    2.0
    """
    r = np.asarray(ring, dtype=np.float64)
    x, y = r[:, 0], r[:, 1]
    # numpy's sums, in their fixed order: np.dot is BLAS's, summed in the order of the
    # kernel BLAS picks for the processor
    return float(0.5 * ((x * np.roll(y, -1)).sum() - (np.roll(x, -1) * y).sum()))


def turned(points: FloatArray, rot: FloatArray) -> FloatArray:
    """``points @ rot.T`` for 2-d points, each coordinate one product and one sum (a
    matrix product is BLAS's, whose rounding depends on the processor: the same seed
    must draw the same world on every machine)."""
    return np.asarray(points[:, :1] * rot[:, 0] + points[:, 1:] * rot[:, 1], dtype=np.float64)


def orient(ring: FloatArray, *, ccw: bool = True) -> FloatArray:
    """The ring in the requested orientation (reversed if needed, first vertex kept)."""
    r = np.asarray(ring, dtype=np.float64)
    if (signed_area(r) > 0) != ccw:
        r = np.concatenate([r[:1], r[:0:-1]])
    return np.ascontiguousarray(r)


def ring_segments(ring: FloatArray) -> FloatArray:
    """Edges of the ring as rows ``(px, py, qx, qy)``; edge i joins vertex i to i + 1."""
    r = np.asarray(ring, dtype=np.float64)
    return np.ascontiguousarray(np.hstack([r, np.roll(r, -1, axis=0)]))


def ring_crossings(ring: FloatArray) -> list[tuple[int, int, tuple[float, float]]]:
    """Pairs of edges of a ring that touch or cross, other than neighbours meeting at
    their shared vertex; each as ``(i, j, point)`` with i < j.

    A neighbouring pair that folds back onto itself (a zero-width spike) is reported too.
    Vectorised over pairs of edges, in blocks of rows so that memory stays bounded.

    Examples
    --------
    >>> ring_crossings([[0, 0], [2, 2], [2, 0], [0, 2]])
    [(0, 2, (1.0, 1.0))]
    """
    segs = ring_segments(np.asarray(ring, dtype=np.float64))
    n = segs.shape[0]
    out: list[tuple[int, int, tuple[float, float]]] = []
    rows = max(1, 2_000_000 // max(n, 1))
    for first in range(0, n, rows):
        out += _crossings_block(segs, first, min(n, first + rows))
    return out


def _crossings_block(
    segs: FloatArray, first: int, last: int
) -> list[tuple[int, int, tuple[float, float]]]:
    n = segs.shape[0]
    i, j = np.nonzero(np.arange(n)[None, :] > np.arange(first, last)[:, None])
    i = i + first
    p, e = segs[i, :2], segs[i, 2:] - segs[i, :2]
    q, f = segs[j, :2], segs[j, 2:] - segs[j, :2]
    w = q - p
    den = e[:, 0] * f[:, 1] - e[:, 1] * f[:, 0]
    scale = np.maximum(np.abs(e).sum(1), 1.0) * np.maximum(np.abs(f).sum(1), 1.0)
    parallel = np.abs(den) <= 1e-12 * scale
    safe = np.where(parallel, 1.0, den)
    s = (w[:, 0] * f[:, 1] - w[:, 1] * f[:, 0]) / safe
    t = (w[:, 0] * e[:, 1] - w[:, 1] * e[:, 0]) / safe
    hit = ~parallel & (s >= 0) & (s <= 1) & (t >= 0) & (t <= 1)
    pts = p + s[:, None] * e
    # Parallel pairs: collinear and overlapping (projection intervals intersect).
    cross_w = np.abs(w[:, 0] * e[:, 1] - w[:, 1] * e[:, 0])
    collinear = parallel & (cross_w <= 1e-12 * scale)
    ee = np.maximum(np.einsum("ij,ij->i", e, e), np.finfo(float).tiny)
    a0 = np.einsum("ij,ij->i", w, e) / ee
    a1 = np.einsum("ij,ij->i", w + f, e) / ee
    lo, hi = np.minimum(a0, a1), np.maximum(a0, a1)
    overlap_lo, overlap_hi = np.maximum(lo, 0.0), np.minimum(hi, 1.0)
    adjacent = (j == i + 1) | ((i == 0) & (j == n - 1))
    # Neighbours share one vertex, so they always "touch"; they are a problem only when
    # they overlap along a stretch (a spike folding back).
    overlap_len = np.where(adjacent, overlap_hi - overlap_lo > 1e-12, overlap_hi >= overlap_lo)
    col_hit = collinear & overlap_len
    pts = np.where(col_hit[:, None], p + np.clip(overlap_lo, 0, 1)[:, None] * e, pts)
    bad = (hit & ~adjacent) | col_hit
    return [
        (int(a), int(b), (float(x), float(y)))
        for a, b, (x, y) in zip(i[bad], j[bad], pts[bad], strict=True)
    ]
