"""Contexts that see motion: a reading and how it changed since the last step, one vector.

The paper's context is the range reading alone (§II-A). A reading cannot tell a disc
coming closer from one going away; the change since the previous step can. With
``LearnParams(motion=True)`` a context is the reading followed by its change, clipped,

    chi = [s_1 .. s_N, c_1 .. c_N],   c_i = clip(s_i - prev_i, -MOTION_CLIP, +MOTION_CLIP),

and the context map (GNG), its skeleton, the symmetry reduction and the priors all live
on this 2N-dimensional space. A symmetry of the ring acts on each block alike (a quarter
turn moves ray i's range *and* its change to ray i + N/4), so the group is the same group
acting on twice the indices (:func:`block_operators`): a template still stands for the
contexts it reaches by a turn or a mirror, now including how they move.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from copi.learning._symmetry import Operator

__all__ = [
    "MOTION_CLIP",
    "block_operators",
    "context_blocks",
    "motion_contexts",
    "previous_in_world",
]

MOTION_CLIP = 1.5
"""A range's change between steps is clipped to +-this (agent steps): an obstacle's step
and the agent's together, beyond which a change says only "something appeared or went"
(the safety model's features clip alike)."""


def context_blocks(motion: bool) -> int:
    """Blocks of N rays in a context: 1 (the reading) or 2 (the reading and its change)."""
    return 2 if motion else 1


def motion_contexts(
    readings: NDArray[np.float64], previous: NDArray[np.float64]
) -> NDArray[np.float64]:
    """Contexts ``[reading, clip(reading - previous)]`` of readings (..., N) after
    ``previous`` (same shape), shape (..., 2N).

    Examples
    --------
    >>> motion_contexts(np.array([1.0, 5.0]), np.array([3.0, 4.5])).tolist()
    [1.0, 5.0, -1.5, 0.5]
    """
    s = np.asarray(readings, dtype=np.float64)
    p = np.asarray(previous, dtype=np.float64)
    return np.concatenate([s, np.clip(s - p, -MOTION_CLIP, MOTION_CLIP)], axis=-1)


def previous_in_world(
    readings: NDArray[np.float64], world: NDArray[np.int64]
) -> NDArray[np.float64]:
    """For readings gathered in world order, the reading before each in the same world
    (a world's first reading is its own previous one: no change seen yet)."""
    prev = np.array(readings, dtype=np.float64, copy=True)
    same = np.asarray(world)[1:] == np.asarray(world)[:-1]
    prev[1:][same] = readings[:-1][same]
    return prev


def block_operators(operators: tuple[Operator, ...], blocks: int) -> tuple[Operator, ...]:
    """The same symmetries acting on ``blocks`` consecutive blocks of N indices alike
    (ray i of every block moves where ray i moves); the plane actions are unchanged.

    Examples
    --------
    >>> from copi.learning._symmetry import ring_operators
    >>> r, _ = block_operators(ring_operators(4), 2)
    >>> r.perm.tolist()
    [3, 0, 1, 2, 7, 4, 5, 6]
    """
    if blocks == 1:
        return tuple(operators)
    out = []
    for op in operators:
        n = len(op.perm)
        perm = np.concatenate([op.perm + b * n for b in range(blocks)])
        out.append(Operator(op.name, perm, op.matrix))
    return tuple(out)
