"""The ``indoor`` world family: rooms, doors and corridors on a random floor plan."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import shapely
from shapely.geometry import Polygon, box

from copi._rng import Seed, as_generator
from copi._validation import FloatArray
from copi.errors import InvalidArgumentError
from copi.world._world import ObstacleSpec, World

__all__ = ["IndoorParams", "indoor_world"]


@dataclass(frozen=True)
class IndoorParams:
    """The distribution of :func:`indoor_world`: a floor plan of rooms and corridors.

    The plan is a grid of ``columns`` x ``rows`` cells whose widths vary: a column (row) is a
    corridor, ``corridor`` wide, with probability ``corridor_share``, else a room, ``room``
    wide. A random depth-first spanning tree over the cells (which makes long winding
    routes, dead ends and U-shaped detours) says which neighbours connect; a connection is
    a door in the wall between them or, with probability ``open_share``, no wall at all
    (rooms merge into L-shapes and corridors run on). With probability ``loop_share`` a
    wall off the tree gets a door too, so some places have two ways in. Walls are
    ``wall`` thick; pieces of wall that touch no outer wall become holes.
    """

    columns: tuple[int, int] = (3, 5)
    """Number of cell columns, uniform inclusive."""
    rows: tuple[int, int] = (2, 4)
    """Number of cell rows, uniform inclusive."""
    room: tuple[float, float] = (5.0, 9.0)
    """Width of a room column or row, in agent steps, uniform."""
    corridor: tuple[float, float] = (2.8, 3.6)
    """Width of a corridor column or row, in agent steps, uniform."""
    corridor_share: float = 0.3
    """Probability that a column or row is a corridor."""
    door: tuple[float, float] = (2.2, 3.0)
    """Door width, in agent steps, uniform (an obstacle of radius 0.8 fits through)."""
    open_share: float = 0.3
    """Probability that two connected cells share no wall."""
    loop_share: float = 0.1
    """Probability that a wall between cells not connected by the tree gets a door."""
    wall: float = 0.3
    """Wall thickness, in agent steps."""
    obstacles: ObstacleSpec = ObstacleSpec(count=(10, 15), radius=(0.4, 0.8))
    """Moving obstacles: the paper's count and speed, radii that fit through doors."""

    def __post_init__(self) -> None:
        for key in ("columns", "rows"):
            lo, hi = getattr(self, key)
            if not (2 <= lo <= hi):
                raise InvalidArgumentError(
                    f"{key} must satisfy 2 <= low <= high; got {getattr(self, key)}"
                )
        for key in ("room", "corridor", "door"):
            lo, hi = getattr(self, key)
            if not (0 < lo <= hi):
                raise InvalidArgumentError(
                    f"{key} must satisfy 0 < low <= high; got {getattr(self, key)}"
                )
        for key in ("corridor_share", "open_share", "loop_share"):
            v = getattr(self, key)
            if not (0 <= v <= 1):
                raise InvalidArgumentError(f"{key} must be in [0, 1]; got {v}")
        if not (0 < self.wall < self.corridor[0]):
            raise InvalidArgumentError(
                f"wall must satisfy 0 < wall < corridor low; got {self.wall}"
            )


def _widths(n: int, p: IndoorParams, rng: np.random.Generator) -> FloatArray:
    corridor = rng.random(n) < p.corridor_share
    return np.where(corridor, rng.uniform(*p.corridor, n), rng.uniform(*p.room, n))


def _spanning_tree(nx: int, ny: int, rng: np.random.Generator) -> set[frozenset[int]]:
    """Edges of a random depth-first spanning tree of the nx x ny grid (cell i + nx j)."""
    seen = np.zeros(nx * ny, dtype=bool)
    start = int(rng.integers(nx * ny))
    stack, seen[start] = [start], True
    edges: set[frozenset[int]] = set()
    while stack:
        c = stack[-1]
        i, j = c % nx, c // nx
        nbrs = [
            (i + di) + nx * (j + dj)
            for di, dj in ((1, 0), (-1, 0), (0, 1), (0, -1))
            if 0 <= i + di < nx and 0 <= j + dj < ny and not seen[(i + di) + nx * (j + dj)]
        ]
        if not nbrs:
            stack.pop()
            continue
        n = nbrs[int(rng.integers(len(nbrs)))]
        seen[n] = True
        edges.add(frozenset((c, n)))
        stack.append(n)
    return edges


def indoor_world(
    seed: Seed = None, *, params: IndoorParams | None = None, name: str | None = None
) -> World:
    """Draw a world of the ``indoor`` family (see :class:`IndoorParams`).

    Examples
    --------
    >>> w = indoor_world(2)
    >>> w == indoor_world(2), w.obstacles.radius
    (True, (0.4, 0.8))
    """
    rng = as_generator(seed)
    p = params or IndoorParams()
    while True:
        nx = int(rng.integers(p.columns[0], p.columns[1] + 1))
        ny = int(rng.integers(p.rows[0], p.rows[1] + 1))
        xs = np.concatenate([[0.0], np.cumsum(_widths(nx, p, rng))])
        ys = np.concatenate([[0.0], np.cumsum(_widths(ny, p, rng))])
        if xs[-1] >= 16.0 and ys[-1] >= 12.0:  # room for a start and goal 10 apart
            break
    tree = _spanning_tree(nx, ny, rng)
    half = p.wall / 2
    walls = []
    # wall between cell (i, j) and its east neighbour, then its north neighbour
    for j in range(ny):
        for i in range(nx):
            c = i + nx * j
            for di, dj in ((1, 0), (0, 1)):
                if i + di >= nx or j + dj >= ny:
                    continue
                linked = frozenset((c, (i + di) + nx * (j + dj))) in tree
                if linked and rng.random() < p.open_share:
                    continue
                door = linked or rng.random() < p.loop_share
                if di:  # vertical wall at x = xs[i + 1] from ys[j] to ys[j + 1]
                    lo, hi, at = ys[j], ys[j + 1], xs[i + 1]
                else:
                    lo, hi, at = xs[i], xs[i + 1], ys[j + 1]
                pieces = [(lo - half, hi + half)]
                if door:
                    width = min(rng.uniform(*p.door), hi - lo - 2 * p.wall)
                    if width < p.door[0]:  # wall too short for a door: leave it open
                        continue
                    d0 = lo + p.wall + rng.uniform(0.0, max(0.0, hi - lo - 2 * p.wall - width))
                    pieces = [(lo - half, d0), (d0 + width, hi + half)]
                for a, b in pieces:
                    walls.append(
                        box(at - half, a, at + half, b) if di else box(a, at - half, b, at + half)
                    )
    room = box(0.0, 0.0, xs[-1], ys[-1])
    free = shapely.difference(room, shapely.union_all(walls)) if walls else room
    free = shapely.simplify(free, 0.0)
    if not isinstance(free, Polygon):  # pragma: no cover - the spanning tree connects all
        free = max(shapely.get_parts(free), key=lambda g: g.area)
    boundary = np.round(np.asarray(free.exterior.coords)[:-1], 6)
    holes = tuple(np.round(np.asarray(r.coords)[:-1], 6) for r in free.interiors)
    label = name or f"indoor-{nx}x{ny}"
    return World(boundary, holes, name=label, obstacles=p.obstacles)
