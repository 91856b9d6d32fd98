"""Navigation meshes (the ShortestPathLab / Polyanya ``.mesh`` format, version 3) as
free space: the union of the traversable convex faces.

``.mesh``: ``mesh``, ``3``, ``n_vertices n_faces``, the vertices (x y, y up), then one
face per line: ``traversable n v_1 .. v_n nb_1 .. nb_n`` with 1-based vertex ids in
counter-clockwise order and neighbour face ids (negative: not crossable, 0: none).
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import shapely
from shapely.geometry import Polygon
from shapely.geometry.base import BaseGeometry

from copi.errors import MapFileError

__all__ = ["read_mesh"]


def read_mesh(path: str | os.PathLike[str]) -> BaseGeometry:
    """The traversable area of a ``.mesh`` file as a Shapely (Multi)Polygon.

    Faces that only share a vertex stay unconnected in a mesh; plan on the result with
    ``VisibilityGraph.from_geometry(..., through_pinch_points=False)`` to keep it so.
    Raises :class:`MapFileError` for a file that is not a version-3 mesh.
    """
    p = Path(path)
    try:
        tokens = p.read_text(encoding="ascii").split()
    except (OSError, UnicodeDecodeError) as exc:
        raise MapFileError(f"{p}: cannot read a navigation mesh ({exc})") from None
    if tokens[:2] != ["mesh", "3"]:
        raise MapFileError(f"{p}: expected 'mesh' and version '3' first; got {tokens[:2]}")
    try:
        n_vertices, n_faces = int(tokens[2]), int(tokens[3])
        i = 4
        vertices = np.array(tokens[i : i + 2 * n_vertices], dtype=float).reshape(n_vertices, 2)
        i += 2 * n_vertices
        faces = []
        for _ in range(n_faces):
            traversable, n = int(tokens[i]), int(tokens[i + 1])
            ids = [int(t) - 1 for t in tokens[i + 2 : i + 2 + n]]
            i += 2 + 2 * n
            if traversable:
                faces.append(Polygon(vertices[ids]))
    except (ValueError, IndexError) as exc:
        raise MapFileError(f"{p}: malformed mesh ({exc})") from None
    if i != len(tokens):
        raise MapFileError(f"{p}: {len(tokens) - i} values left after {n_faces} faces")
    return shapely.union_all(faces)
