"""The move of a ``compass`` policy (:class:`copi.baselines.PolicyWeights` with
``output="compass"``, a classifier cloned from a demonstrator's moves): the best of its
scores, one a ray of its frame and one for standing still."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import NDArray

__all__ = ["compass_move"]


def compass_move(values: Any, x: Any, n_rays: int, max_range: float) -> NDArray[np.float64]:
    """The move of a ``compass`` policy in its frame: the best of its ``n_rays + 1``
    ``values`` (the first of equals), a step along that ray of the frame, or none for the
    last. The step's length is compass-guard's rule, hand-written: a full step, unless the
    point aimed at (the observation ``x``'s last three values: the direction in the frame
    and the reach over the range) is nearer than one step; then as far as coming level
    with it, and at least half the way.

    Examples
    --------
    >>> x = np.array([1.0, 0.0, 0.05])   # aiming along +x, 0.5 away (range 10)
    >>> compass_move([0.0, 2.0, 0.0, 0.0, 0.0], x, 4, 10.0).round(3).tolist()  # along +y
    [0.0, 0.25]
    >>> compass_move([0.0, 0.0, 0.0, 0.0, 1.0], x, 4, 10.0).tolist()  # standing still
    [0.0, 0.0]
    """
    m = int(np.argmax(np.asarray(values)))
    if m >= n_rays:
        return np.zeros(2)
    a = 2 * math.pi * m / n_rays
    ax, ay = math.cos(a), math.sin(a)
    reach = float(x[-1]) * max_range
    step = 1.0
    if reach < 1.0:  # the aim is nearer than one step (x[-1] is clipped to 1 beyond the range)
        step = max((ax * float(x[-3]) + ay * float(x[-2])) * reach, 0.5 * reach)
    return np.array([ax * step, ay * step])
