"""Ray casting against segments and discs (the range sensor's geometry)."""

from __future__ import annotations

from typing import Any

import numpy as np

from copi._validation import FloatArray, as_discs, as_points, as_segments, as_vector, positive
from copi.errors import InvalidArgumentError
from copi.geometry import kernels

__all__ = ["cast_rays", "ring_angles"]


def ring_angles(n_rays: int = 32) -> FloatArray:
    """Angles of a ring of ``n_rays`` rays: ray i points at 2 pi i / n counter-clockwise
    from +x (docs/design.md, "Sensor ring").

    Examples
    --------
    >>> ring_angles(4).round(4).tolist()
    [0.0, 1.5708, 3.1416, 4.7124]
    """
    if int(n_rays) != n_rays or n_rays < 1:
        raise InvalidArgumentError(f"n_rays must be a positive int; got {n_rays!r}")
    return 2.0 * np.pi * np.arange(int(n_rays)) / int(n_rays)


def cast_rays(
    origins: Any,
    angles: Any,
    segments: Any,
    centers: Any = None,
    radii: Any = None,
    *,
    max_range: float = 10.0,
) -> FloatArray:
    """Range of each ray from each origin to the first segment or disc it meets.

    Parameters
    ----------
    origins : array_like of shape (2,) or (b, 2)
        Ray origins, in agent steps.
    angles : array_like of shape (n,)
        Ray directions in radians, counter-clockwise from +x; the same for every origin.
    segments : array_like of shape (m, 4)
        Wall segments, rows ``(px, py, qx, qy)``.
    centers, radii : array_like of shape (d, 2) and (d,) or scalar, optional
        Discs (moving obstacles). An origin inside a disc reads 0 on every ray.
    max_range : float
        Rays that meet nothing closer read ``max_range``.

    Returns
    -------
    ndarray of shape (n,) or (b, n)
        Ranges in agent steps, in [0, max_range]; (n,) when one origin of shape (2,) is given.

    Examples
    --------
    >>> square = [[0, 0, 4, 0], [4, 0, 4, 4], [4, 4, 0, 4], [0, 4, 0, 0]]
    >>> cast_rays([1.0, 1.0], ring_angles(4), square).round(6).tolist()
    [3.0, 3.0, 1.0, 1.0]
    >>> cast_rays([1.0, 1.0], [0.0], square, [[2.5, 1.0]], 0.5).tolist()
    [1.0]
    """
    pts = np.asarray(origins, dtype=np.float64)
    single = pts.ndim == 1
    ang = np.asarray(angles, dtype=np.float64)
    segs = np.asarray(segments, dtype=np.float64)
    if centers is None and radii is None:
        c, r = _NO_CENTERS, _NO_RADII
    else:
        c = np.asarray(centers, dtype=np.float64)
        r = np.asarray(radii, dtype=np.float64)
        if r.ndim == 0 and c.ndim == 2:
            r = np.full(c.shape[0], float(r))
    shapes_ok = (
        pts.shape[-1:] == (2,)
        and pts.ndim in (1, 2)
        and ang.ndim == 1
        and segs.ndim == 2
        and segs.shape[1] == 4
        and c.ndim == 2
        and c.shape[1] == 2
        and r.shape == (c.shape[0],)
        and isinstance(max_range, int | float)
    )
    if shapes_ok:
        # Fast path: shapes checked above, values checked inside the compiled call.
        batch = pts[None] if single else pts
        out = np.empty((batch.shape[0], ang.shape[0]))
        if kernels.scan_checked(
            batch, np.cos(ang), np.sin(ang), segs, c, r, float(max_range), out
        ):
            return out[0] if single else out
    # Something is off: validate one argument at a time to say exactly what.
    pts, single = as_points(origins, "origins")
    ang = as_vector(angles, "angles")
    segs = as_segments(segments)
    c, r = as_discs(centers, radii)
    mr = positive(max_range, "max_range")
    out = np.empty((pts.shape[0], ang.shape[0]))
    kernels.scan(pts, np.cos(ang), np.sin(ang), segs, c, r, mr, out)
    return out[0] if single else out


_NO_CENTERS = np.zeros((0, 2))
_NO_RADII = np.zeros(0)
