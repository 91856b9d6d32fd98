"""Moving AI grid benchmarks (Sturtevant 2012): ``.map`` and ``.scen`` files, and maps
as copi worlds.

``.map``: ``type octile``, ``height H``, ``width W``, ``map``, then H rows of W characters;
cell (x, y) is column x, row y, (0, 0) top-left. Passable: ``.`` and ``G`` (also ``S``
and ``W``, swamp and water, are treated as blocked, as in the octile benchmarks); blocked:
``@``, ``O``, ``T``. ``.scen``: ``version 1`` then rows ``bucket map width height sx sy
gx gy optimal_length`` (tabs or spaces).
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import shapely
from shapely.geometry import MultiPolygon, Polygon

from copi.errors import InvalidWorldError, MapFileError
from copi.world import World
from copi.world.gridmap import (  # noqa: F401 - re-exported
    BLOCKED,
    PASSABLE,
    GridMap,
    cell_center,
    free_geometry,
    read_map,
    without_pinches,
)

__all__ = [
    "GridMap",
    "Scenario",
    "cell_center",
    "free_geometry",
    "map_world",
    "read_map",
    "read_scenarios",
]


@dataclass(frozen=True)
class Scenario:
    """One line of a ``.scen`` file."""

    bucket: int
    map_name: str
    width: int
    height: int
    start: tuple[int, int]
    goal: tuple[int, int]
    optimal_length: float
    line: int
    """Line number in the file (1-based), for messages."""


def read_scenarios(path: str | os.PathLike[str]) -> list[Scenario]:
    """Read a ``.scen`` file (version 1 or 1.0; tab- or space-separated)."""
    p = Path(path)
    try:
        lines = p.read_text(encoding="ascii").splitlines()
    except (OSError, UnicodeDecodeError) as exc:
        raise MapFileError(f"{p}: cannot read a Moving AI scenario file ({exc})") from None
    if not lines or not lines[0].startswith("version"):
        raise MapFileError(f"{p}:1: expected 'version 1' first; got {lines[0] if lines else ''!r}")
    out = []
    for n, line in enumerate(lines[1:], start=2):
        if not line.strip():
            continue
        f = line.split("\t") if "\t" in line else line.split()
        if len(f) != 9:
            raise MapFileError(f"{p}:{n}: expected 9 fields; found {len(f)}")
        try:
            out.append(
                Scenario(
                    bucket=int(f[0]),
                    map_name=f[1],
                    width=int(f[2]),
                    height=int(f[3]),
                    start=(int(f[4]), int(f[5])),
                    goal=(int(f[6]), int(f[7])),
                    optimal_length=float(f[8]),
                    line=n,
                )
            )
        except ValueError as exc:
            raise MapFileError(f"{p}:{n}: {exc}") from None
    return out


def map_world(grid: GridMap, *, near: tuple[int, int] | None = None) -> World:
    """A map's free space as a :class:`~copi.world.World`: the connected region holding
    cell ``near`` (the largest region by default), its walls and holes.

    The free space is shrunk by a hair (:func:`~copi.world.gridmap.without_pinches`), so
    that blocked cells touching only at a corner become one hole."""
    geom = without_pinches(free_geometry(grid))
    parts = list(geom.geoms) if isinstance(geom, MultiPolygon) else [geom]
    parts = [g for g in parts if isinstance(g, Polygon) and not g.is_empty]
    if not parts:
        raise InvalidWorldError(f"map {grid.name}: no free cell")
    if near is None:
        region = shapely.simplify(max(parts, key=lambda g: g.area), 0.0)
    else:
        c = cell_center(grid, near)
        inside = [g for g in parts if shapely.intersects_xy(g, c[0], c[1])]
        if not inside:
            raise InvalidWorldError(f"map {grid.name}: cell {near} is not free")
        region = inside[0]
    return World(
        np.asarray(region.exterior.coords)[:-1],
        tuple(np.asarray(r.coords, dtype=np.float64)[:-1] for r in region.interiors),
        name=Path(grid.name).stem,
    )
