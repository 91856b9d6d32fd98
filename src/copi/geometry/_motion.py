"""Discs moving among walls: stop at the first contact, clearance to walls."""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from copi._validation import FloatArray, as_points, as_segments, positive
from copi.errors import InvalidArgumentError
from copi.geometry import kernels

__all__ = ["clearance", "move_discs"]


def move_discs(
    positions: Any, velocities: Any, segments: Any, radius: float
) -> tuple[FloatArray, NDArray[np.bool_]]:
    """Move discs of ``radius`` by ``velocities``, each stopping at the first wall it meets.

    The disc's centre travels along its velocity until the disc would touch a segment
    (exact swept-disc test: the centre's ray against the segment's capsule of ``radius``),
    and stops a hair (1e-9) short of it, so a disc never passes through a wall. A disc
    resting against a wall can still slide along it or move away.

    Parameters
    ----------
    positions, velocities : array_like of shape (2,) or (b, 2)
        Centres before the move and displacements for this step, in agent steps.
    segments : array_like of shape (m, 4)
        Walls, rows ``(px, py, qx, qy)``.
    radius : float
        Disc radius, > 0.

    Returns
    -------
    positions : ndarray of shape (2,) or (b, 2)
    blocked : bool or ndarray of shape (b,)
        Whether a wall stopped the disc short of its full displacement.

    Examples
    --------
    >>> wall = [[2.0, -5.0, 2.0, 5.0]]
    >>> p, blocked = move_discs([0.0, 0.0], [3.0, 0.0], wall, 0.5)
    >>> p.round(6).tolist(), bool(blocked)
    ([1.5, 0.0], True)
    """
    pos, single = as_points(positions, "positions")
    vel, _ = as_points(velocities, "velocities")
    if vel.shape != pos.shape:
        raise InvalidArgumentError(
            f"velocities must have the shape of positions {pos.shape}; got {vel.shape}"
        )
    segs = as_segments(segments)
    r = positive(radius, "radius")
    out = np.empty((pos.shape[0], 3))
    kernels.move(pos, vel, segs, r, out)
    new, blocked = out[:, :2].copy(), out[:, 2] > 0.5
    return (new[0], blocked[0]) if single else (new, blocked)


def clearance(points: Any, segments: Any) -> FloatArray:
    """Distance from each point to the nearest segment.

    Examples
    --------
    >>> clearance([[0.0, 3.0], [5.0, 0.0]], [[-1.0, 0.0, 1.0, 0.0]]).tolist()
    [3.0, 4.0]
    """
    pts, single = as_points(points, "points")
    segs = as_segments(segments)
    out = np.empty(pts.shape[0])
    if segs.shape[0] == 0:
        out[:] = np.inf
    else:
        kernels.clearance(pts, segs, out)
    return out[0] if single else out
