"""Named small worlds shared by the tests (like Shapely's tests/common.py)."""

from __future__ import annotations

from pathlib import Path

from copi.world import PACKAGED_MAPS, World

DATA = Path(__file__).resolve().parent / "data"
"""Reference data nobody on copi wrote (provenance and licences in its README)."""

MAPS = PACKAGED_MAPS
"""The Moving AI maps copi ships (the ``maps`` family's, and the scenarios' in DATA)."""

SQUARE_ROOM = World([[0, 0], [20, 0], [20, 20], [0, 20]], name="square-room")
"""An empty 20 x 20 room."""

CORRIDOR = World([[0, 0], [40, 0], [40, 3], [0, 3]], name="corridor")
"""A 40 x 3 corridor: walls on both sides within sensor range."""

U_TRAP = World(
    [[0, 0], [40, 0], [40, 30], [0, 30]],
    [[[10, 5], [30, 5], [30, 25], [28, 25], [28, 7], [12, 7], [12, 25], [10, 25]]],
    name="u-trap",
    start=[20, 15],
    goal=[20, 28],
)
"""The design page's example: the start sits inside a U that opens towards the goal."""

PILLARS = World(
    [[0, 0], [30, 0], [30, 30], [0, 30]],
    [
        [[5, 5], [9, 5], [9, 9], [5, 9]],
        [[15, 12], [19, 15], [15, 18]],
        [[22, 22], [26, 22], [26, 26], [22, 26]],
    ],
    name="pillars",
)
"""A room with three convex holes (two squares and a triangle)."""

WALL = World(
    [[0, 0], [30, 0], [30, 30], [0, 30]],
    [[[9, 14], [21, 14], [21, 15], [9, 15]]],
    name="wall",
    start=[15, 5],
    goal=[15, 25],
)
"""A 30 x 30 room with a 12-long wall across the straight line from start to goal; the
way round is past either end (the wall is 9 ahead of the start, its ends 11 aside)."""

NAMED = {w.name: w for w in (SQUARE_ROOM, CORRIDOR, U_TRAP, PILLARS, WALL)}
