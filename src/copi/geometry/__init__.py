"""Vectorised geometry of the navigation domain: rays, discs, walls, polygon rings.

Free functions over arrays, nothing with state. Lengths are in agent steps,
angles in radians counter-clockwise from +x. A wall segment is a row ``(px, py, qx, qy)``.
"""

from __future__ import annotations

from copi.geometry._motion import clearance, move_discs
from copi.geometry._polygons import (
    as_ring,
    orient,
    ring_crossings,
    ring_segments,
    signed_area,
    turned,
)
from copi.geometry._rays import cast_rays, ring_angles

__all__ = [
    "as_ring",
    "cast_rays",
    "clearance",
    "move_discs",
    "orient",
    "ring_angles",
    "ring_crossings",
    "ring_segments",
    "signed_area",
    "turned",
]
