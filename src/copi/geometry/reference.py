"""Straightforward implementations of copi's geometry, for checking and measuring.

These are slow on purpose: each is written the obvious way with a well-known library, so
that tests can compare the compiled kernels against something independent, and the
benchmarks can report how much faster the kernels are (``benchmarks/bench_world.py``).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import shapely

from copi._validation import FloatArray

__all__ = ["cast_rays_numpy", "cast_rays_shapely"]


def cast_rays_shapely(
    origin: Any,
    angles: Any,
    segments: Any,
    centers: Any = None,
    radii: Any = None,
    *,
    max_range: float = 10.0,
    quad_segs: int = 64,
) -> FloatArray:
    """One scan with Shapely 2: each ray a LineString, intersected with the walls and
    the discs' boundaries (polygons of ``4 * quad_segs`` sides, inscribed in the circles,
    so a disc reads slightly far and a grazing ray may miss it)."""
    o = np.asarray(origin, dtype=float)
    ang = np.asarray(angles, dtype=float)
    ends = o + max_range * np.column_stack([np.cos(ang), np.sin(ang)])
    rays = shapely.linestrings(
        np.stack([np.broadcast_to(o, ends.shape), ends], axis=1)  # (n, 2, 2)
    )
    origin_pt = shapely.points(o)
    walls = shapely.multilinestrings(np.asarray(segments, dtype=float).reshape(-1, 2, 2))
    best = shapely.distance(origin_pt, shapely.intersection(rays, walls))  # NaN: no hit
    if centers is not None and len(centers):
        c = np.asarray(centers, dtype=float).reshape(-1, 2)
        r = np.broadcast_to(np.asarray(radii, dtype=float), (len(c),))
        discs = shapely.buffer(shapely.points(c), r, quad_segs=quad_segs)
        if shapely.contains_xy(discs, o[0], o[1]).any():
            return np.zeros(len(ang))
        rims = shapely.multilinestrings(shapely.get_exterior_ring(discs))
        best = np.fmin(best, shapely.distance(origin_pt, shapely.intersection(rays, rims)))
    return np.where(np.isnan(best), max_range, np.minimum(best, max_range))


def cast_rays_numpy(
    origins: Any,
    angles: Any,
    segments: Any,
    centers: Any = None,
    radii: Any = None,
    *,
    max_range: float = 10.0,
) -> FloatArray:
    """Scans from many origins with plain numpy broadcasting over (origins, rays,
    segments) and (origins, rays, discs); returns shape (b, n)."""
    o = np.atleast_2d(np.asarray(origins, dtype=float))[:, None, None, :]  # (b,1,1,2)
    ang = np.asarray(angles, dtype=float)
    d = np.stack([np.cos(ang), np.sin(ang)], axis=-1)[None, :, None, :]  # (1,n,1,2)
    s = np.asarray(segments, dtype=float)
    p, e = s[None, None, :, :2], (s[:, 2:] - s[:, :2])[None, None]  # (1,1,m,2)
    w = p - o
    den = d[..., 0] * e[..., 1] - d[..., 1] * e[..., 0]
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (w[..., 0] * e[..., 1] - w[..., 1] * e[..., 0]) / den
        u = (w[..., 0] * d[..., 1] - w[..., 1] * d[..., 0]) / den
    t = np.where((den != 0) & (t >= 0) & (u >= 0) & (u <= 1), t, np.inf)
    best = np.minimum(t.min(axis=-1), max_range)
    if centers is not None and len(centers):
        c = np.asarray(centers, dtype=float).reshape(-1, 2)[None, None]
        r = np.broadcast_to(np.asarray(radii, dtype=float), (c.shape[2],))
        v = o - c
        b = (d * v).sum(-1)
        cc = (v * v).sum(-1) - r**2
        disc = b * b - cc
        with np.errstate(invalid="ignore"):
            tc = -b - np.sqrt(disc)
        tc = np.where((cc > 0) & (b < 0) & (disc >= 0), tc, np.inf)
        tc = np.where(cc <= 0, 0.0, tc)
        best = np.minimum(best, tc.min(axis=-1))
    return best
