"""Moving AI grid maps (Sturtevant 2012) read as free space: ``.map`` files.

``.map``: ``type octile``, ``height H``, ``width W``, ``map``, then H rows of W characters;
cell (x, y) is column x, row y, (0, 0) top-left. Passable: ``.`` and ``G`` (also ``S``
and ``W``, swamp and water, are treated as blocked, as in the octile benchmarks); blocked:
``@``, ``O``, ``T``.

Lives in :mod:`copi.world` so that world families can cut worlds out of maps; the
planning side (:mod:`copi.planning.movingai`) re-exports these names with its scenarios.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from typing import Any

import numpy as np
import shapely
from numpy.typing import NDArray
from shapely.geometry import MultiPolygon, Polygon, box

from copi._files import regular_file
from copi.errors import MapFileError
from copi.world._world import MAX_VERTICES

__all__ = [
    "BLOCKED",
    "PASSABLE",
    "GridMap",
    "cell_center",
    "corner_count",
    "free_geometry",
    "read_map",
]

PASSABLE = frozenset(".G")
BLOCKED = frozenset("@OTSW")
HEADER_KEYS = ("type", "height", "width")
"""The keys of a Moving AI map's header."""
MAX_SIDE = 8192
"""The largest height or width of a map read (Moving AI's largest are 1024 x 1024)."""


@dataclass(frozen=True, eq=False)
class GridMap:
    """A Moving AI map: ``free[y, x]`` is True for a passable cell."""

    name: str
    free: NDArray[np.bool_]

    @property
    def height(self) -> int:
        return int(self.free.shape[0])

    @property
    def width(self) -> int:
        return int(self.free.shape[1])


def read_map(path: str | os.PathLike[str]) -> GridMap:
    """Read a ``.map`` file; a malformed one raises :class:`MapFileError` with its line."""
    p = regular_file(path, "Moving AI map", MapFileError)
    try:
        size = p.stat().st_size
    except OSError as exc:
        raise MapFileError(f"{p}: cannot read a Moving AI map ({exc.strerror or exc})") from None
    if size > (MAX_SIDE + 2) * (MAX_SIDE + 1) + 4096:
        raise MapFileError(
            f"{p}: {size:,} bytes, more than a map of at most {MAX_SIDE} x {MAX_SIDE} cells holds"
        )
    try:
        lines = p.read_text(encoding="ascii").splitlines()
    except (OSError, UnicodeDecodeError) as exc:
        raise MapFileError(f"{p}: cannot read a Moving AI map ({exc})") from None
    header: dict[str, str] = {}
    i = 0
    while i < len(lines) and lines[i].strip() != "map":
        parts = lines[i].split()
        if len(parts) != 2:
            raise MapFileError(
                f"{p}:{i + 1}: expected 'key value' header or 'map'; got {lines[i]!r}"
            )
        if parts[0] in header:
            raise MapFileError(f"{p}:{i + 1}: the header gives {parts[0]!r} twice")
        if parts[0] not in HEADER_KEYS:
            raise MapFileError(f"{p}:{i + 1}: unknown header key {parts[0]!r}; a Moving AI map "
                               f"has {', '.join(HEADER_KEYS)}")  # fmt: skip
        header[parts[0]] = parts[1]
        i += 1
    if i == len(lines):
        raise MapFileError(f"{p}: no 'map' line; not a Moving AI map")
    if header.get("type", "octile") != "octile":
        raise MapFileError(f"{p}: type must be octile (a grid of square cells); got "
                           f"{header['type']!r}")  # fmt: skip
    try:
        h, w = int(header["height"]), int(header["width"])
    except (KeyError, ValueError):
        raise MapFileError(
            f"{p}: header must give integer 'height' and 'width'; got {header}"
        ) from None
    if not (1 <= h <= MAX_SIDE and 1 <= w <= MAX_SIDE):
        raise MapFileError(
            f"{p}: height and width must be in 1 .. {MAX_SIDE} cells; got height {h}, width {w}"
        )
    rows = lines[i + 1 : i + 1 + h]
    if len(rows) != h:
        raise MapFileError(f"{p}: expected {h} map rows; found {len(rows)}")
    extra = [k for k, line in enumerate(lines[i + 1 + h :]) if line.strip()]
    if extra:
        raise MapFileError(f"{p}:{i + 2 + h + extra[0]}: more rows than the header's height "
                           f"{h}")  # fmt: skip
    grid = np.zeros((h, w), dtype=bool)
    for y, row in enumerate(rows):
        if len(row) != w:
            what = " (trailing spaces?)" if row[w:].strip() == "" and len(row) > w else ""
            raise MapFileError(
                f"{p}:{i + 2 + y}: expected {w} cells, as the header's width says; found "
                f"{len(row)}{what}"
            )
        chars = set(row[:w])
        unknown = chars - PASSABLE - BLOCKED
        if unknown:
            raise MapFileError(f"{p}:{i + 2 + y}: unknown cell characters {sorted(unknown)}")
        grid[y] = [c in PASSABLE for c in row[:w]]
    if not grid.any():
        raise MapFileError(f"{p}: no passable cell ('.' or 'G'): nothing to move in")
    return GridMap(p.name, grid)


def cell_center(grid: GridMap, cell: tuple[int, int]) -> NDArray[np.float64]:
    """World coordinates of a cell's centre. Cell (x, y) is the unit square
    [x, x + 1] x [H - 1 - y, H - y]: y points up in worlds, down in map files."""
    x, y = cell
    return np.array([x + 0.5, grid.height - y - 0.5])


def corner_count(free: NDArray[np.bool_]) -> int:
    """The vertices the free space of a grid (``free[y, x]``) has as polygons: grid
    points where one or three of the four cells around are free, and twice those where
    two diagonal ones are (a pinch). Counted in a few array operations, so that a map too
    fine for a world is refused before its geometry is built."""
    p = np.pad(free, 1).astype(np.int8)
    a, b, c, d = p[:-1, :-1], p[:-1, 1:], p[1:, :-1], p[1:, 1:]
    s = a + b + c + d
    pinch = (s == 2) & (a == d)
    return int(np.count_nonzero((s == 1) | (s == 3)) + 2 * np.count_nonzero(pinch))


def free_geometry(grid: GridMap) -> Polygon | MultiPolygon:
    """The closed free space of a map in world coordinates (blocked cells are closed
    unit squares; see :func:`cell_center`)."""
    corners = corner_count(grid.free)
    if corners > MAX_VERTICES:
        raise MapFileError(
            f"{grid.name}: its free space has {corners:,} corners, more than the "
            f"{MAX_VERTICES:,} vertices a world may have (copi's sensor and planner go "
            "through every wall edge); crop the map, or read it as a grid"
        )
    h, w = grid.free.shape
    runs = []
    for y in range(h):
        row = ~grid.free[y]
        if not row.any():
            continue
        edges = np.flatnonzero(np.diff(np.concatenate([[0], row.astype(np.int8), [0]])))
        top = h - y
        runs += [box(a, top - 1, b, top) for a, b in zip(edges[::2], edges[1::2], strict=True)]
    region = box(0, 0, w, h)
    if not runs:
        return region
    return shapely.difference(region, shapely.union_all(runs))


PINCH = 1e-3
"""How far :func:`without_pinches` shrinks free space, in map cells (or world units)."""


def without_pinches(free: Any) -> Any:
    """Free space shrunk by a hair (:data:`PINCH`, mitred corners): blocked cells meeting
    only at a corner make holes that touch each other or the boundary at a point (a
    valid Shapely polygon, not a valid world); shrinking merges them and cuts the
    zero-width pinches in between."""
    return shapely.buffer(free, -PINCH, join_style="mitre")
