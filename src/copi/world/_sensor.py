"""The ring range sensor (paper §IV: "a set of 32 ring-arranged range-sensors")."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from copi._validation import FloatArray, positive_int
from copi.errors import InvalidArgumentError
from copi.geometry import cast_rays, ring_angles
from copi.world._world import World

__all__ = ["MAX_RAYS", "RangeSensor"]

MAX_RAYS = 4096
MAX_RANGE = 1000.0
"""Farthest a ring may read, agent steps (worlds are at most 1e6 across; a range beyond
this is a slip, and one near 1e300 overflows the geometry)."""
"""Most rays a ring may have (copi's is 32; 4,096 is a ray every 0.09 degrees)."""


@dataclass(frozen=True)
class RangeSensor:
    """N range rays fixed to the world frame, ray i at angle 2 pi i / N from +x.

    The navigation agent has no heading, so the ring does not turn with it (docs/design.md).
    Ranges are measured from the agent's centre to the first wall, hole edge or moving
    disc, clipped to ``max_range``; a centre inside a disc reads 0 everywhere.

    Examples
    --------
    >>> box = World([[0, 0], [20, 0], [20, 20], [0, 20]])
    >>> RangeSensor(4).scan(box, [5.0, 15.0]).tolist()
    [10.0, 5.0, 5.0, 10.0]
    """

    n_rays: int = 32
    """Number of rays N."""
    max_range: float = 10.0
    """Readings are clipped to this range, in agent steps."""
    angles: FloatArray = field(init=False, repr=False, compare=False)
    cos: FloatArray = field(init=False, repr=False, compare=False)
    sin: FloatArray = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        positive_int(self.n_rays, "n_rays")
        if self.n_rays > MAX_RAYS:
            raise InvalidArgumentError(
                f"n_rays must be at most {MAX_RAYS:,} (a ring of more is a typing error, not "
                f"a sensor); got {self.n_rays:,}"
            )
        mr = float(self.max_range)
        if not np.isfinite(mr) or not 0 < mr <= MAX_RANGE:
            raise InvalidArgumentError(f"max_range must be a number in (0, {MAX_RANGE:g}] agent "
                                       f"steps; got {mr:g}")  # fmt: skip
        object.__setattr__(self, "n_rays", int(self.n_rays))
        object.__setattr__(self, "max_range", mr)
        angles = ring_angles(self.n_rays)
        for name, arr in (("angles", angles), ("cos", np.cos(angles)), ("sin", np.sin(angles))):
            arr = np.ascontiguousarray(arr)
            arr.setflags(write=False)
            object.__setattr__(self, name, arr)

    def scan(
        self, world: World, positions: Any, centers: Any = None, radii: Any = None
    ) -> FloatArray:
        """Readings from one position (2,) -> (N,), or many (b, 2) -> (b, N), at once.

        ``centers``/``radii`` are the moving obstacles' discs, shared by all positions.
        """
        return cast_rays(
            positions, self.angles, world.segments, centers, radii, max_range=self.max_range
        )
