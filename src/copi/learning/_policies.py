"""Local policy templates for the reduced landmarks (paper §II-D)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np
from numpy.typing import NDArray

from copi.errors import CopiError, InvalidArgumentError
from copi.geometry import ring_angles
from copi.planning import shortest_path
from copi.world import World

__all__ = [
    "ActionPriors",
    "AStarLearner",
    "PolicyLearner",
    "PolicySet",
    "ValueIterationLearner",
    "compass",
    "local_world",
]

_NAMES = {
    4: ["E", "N", "W", "S"],
    8: ["E", "NE", "N", "NW", "W", "SW", "S", "SE"],
    16: [
        "E",
        "ENE",
        "NE",
        "NNE",
        "N",
        "NNW",
        "NW",
        "WNW",
        "W",
        "WSW",
        "SW",
        "SSW",
        "S",
        "SSE",
        "SE",
        "ESE",
    ],
}


def compass(n: int) -> tuple[list[str], NDArray[np.float64]]:
    """Names and unit vectors of ``n`` compass directions (4, 8 or 16), E first, then
    counter-clockwise.

    Examples
    --------
    >>> names, vecs = compass(4)
    >>> names, vecs.round(6).tolist()
    (['E', 'N', 'W', 'S'], [[1.0, 0.0], [0.0, 1.0], [-1.0, 0.0], [-0.0, -1.0]])
    """
    if n not in _NAMES:
        raise InvalidArgumentError(f"directions must be 4, 8 or 16; got {n}")
    a = 2 * np.pi * np.arange(n) / n
    return list(_NAMES[n]), np.column_stack([np.cos(a), np.sin(a)])


def local_world(ranges: Any, max_range: float, *, min_range: float = 0.05) -> World:
    """The small stationary world a context stands for (§II-D: "the landmark context is
    treated as a stationary, isolated and restricted environment"): the star-shaped
    polygon through the end points of the rays, centred on the agent at the origin.
    Rays at the maximum range end on the window's edge, which counts as open.

    Readings below ``min_range`` are raised to it, so that the polygon keeps an area.
    """
    r = np.maximum(np.asarray(ranges, dtype=np.float64), min_range)
    a = ring_angles(len(r))
    return World(np.column_stack([r * np.cos(a), r * np.sin(a)]), name="context")


@dataclass(frozen=True, eq=False)
class PolicySet:
    """The local policies of every template, in the template's own frame.

    Policy (t, d) moves the agent out of template t's window in compass direction d.
    """

    names: list[str]
    """Direction names, e.g. E, N, W, S."""
    directions: NDArray[np.float64]
    """Unit vectors of the directions, shape (n_directions, 2)."""
    passable: NDArray[np.bool_]
    """Whether template t has a policy for direction d, shape (n_templates, n_directions)."""
    actions: NDArray[np.float64]
    """First move of each policy, a unit vector (zero when impassable), shape
    (n_templates, n_directions, 2)."""
    lengths: NDArray[np.float64]
    """Length of each policy's path to the window's edge (inf when impassable)."""
    path_xy: NDArray[np.float64]
    """All policies' waypoints, one after another, shape (n_points, 2)."""
    path_start: NDArray[np.int64]
    """Policy (t, d)'s waypoints are path_xy[path_start[i]:path_start[i + 1]] with
    i = t * n_directions + d; shape (n_templates * n_directions + 1,)."""
    learner: str
    """Which learner made them."""

    def path(self, template: int, direction: int) -> NDArray[np.float64]:
        """Waypoints of one policy (empty when impassable)."""
        i = template * len(self.names) + direction
        return self.path_xy[self.path_start[i] : self.path_start[i + 1]]

    @property
    def n_policies(self) -> int:
        return int(self.passable.sum())


class PolicyLearner(Protocol):
    """Learns one policy per (template, direction) from the templates' readings."""

    name: str

    def learn(
        self, templates: NDArray[np.float64], max_range: float, n_directions: int
    ) -> PolicySet: ...


def _exit_target(
    ranges: NDArray[np.float64], u: NDArray[np.float64], n_dirs: int, reach: float, margin: float
) -> NDArray[np.float64] | None:
    """Where policy "go in direction u" aims: along the ray nearest to u, within half a
    sector of it, whose reading is at least ``reach``, ``margin`` short of the wall it
    sees; None (impassable) when no ray of the sector reaches that far."""
    a = ring_angles(len(ranges))
    diff = np.abs((a - math.atan2(u[1], u[0]) + np.pi) % (2 * np.pi) - np.pi)
    ok = (ranges >= reach) & (diff <= np.pi / n_dirs + 1e-9)
    if not ok.any():
        return None
    i = int(np.flatnonzero(ok)[np.argmin(diff[ok])])
    return (ranges[i] - margin) * np.array([math.cos(a[i]), math.sin(a[i])])


def _pack(
    names: list[str],
    dirs: NDArray[np.float64],
    paths: list[list[NDArray[np.float64] | None]],
    learner: str,
) -> PolicySet:
    t, d = len(paths), len(names)
    passable = np.zeros((t, d), dtype=bool)
    actions = np.zeros((t, d, 2))
    lengths = np.full((t, d), np.inf)
    chunks: list[NDArray[np.float64]] = []
    start = [0]
    for i, row in enumerate(paths):
        for j, p in enumerate(row):
            if p is not None and len(p) >= 2:
                passable[i, j] = True
                step = p[1] - p[0]
                actions[i, j] = step / np.hypot(step[0], step[1])  # not norm: BLAS's dot
                lengths[i, j] = float(np.hypot(*np.diff(p, axis=0).T).sum())
                chunks.append(p)
                start.append(start[-1] + len(p))
            else:
                start.append(start[-1])
    xy = np.concatenate(chunks) if chunks else np.zeros((0, 2))
    return PolicySet(names, dirs, passable, actions, lengths, xy, np.array(start), learner)


@dataclass(frozen=True)
class AStarLearner:
    """The paper's learner: in each template's local world, the shortest path (A* on the
    visibility graph of the configuration space, :func:`copi.planning.shortest_path`) from
    the agent's position to the window's open edge in each direction."""

    agent_radius: float = 0.3
    """Radius of the disc agent. When a template's walls are nearer than that (the
    landmark is an average of readings, some touching a wall), 90 % of the nearest
    reading is used instead."""
    margin: float = 0.5
    """How far short of the wall (or of the window's edge) the exit point lies, beyond
    the agent radius."""
    reach: float = 0.5
    """A direction is passable when some ray of its sector reads at least this fraction
    of the sensor range: there is room to travel that far that way. (Landmarks are
    averages of many readings, so a reading of exactly the maximum is rare.)"""
    name: str = "astar"

    def learn(
        self, templates: NDArray[np.float64], max_range: float, n_directions: int
    ) -> PolicySet:
        names, dirs = compass(n_directions)
        paths: list[list[NDArray[np.float64] | None]] = []
        for ranges in np.asarray(templates, dtype=np.float64):
            world = local_world(ranges, max_range)
            radius = min(self.agent_radius, 0.9 * float(world.clearance(np.zeros(2))))
            row: list[NDArray[np.float64] | None] = []
            for u in dirs:
                target = _exit_target(
                    ranges, u, n_directions, self.reach * max_range, self.margin + radius
                )
                plan = None
                if target is not None:
                    try:
                        plan = shortest_path(world, np.zeros(2), target, radius=radius, quad_segs=4)
                    except CopiError:
                        plan = None
                row.append(plan.path if plan is not None and plan.found else None)
            paths.append(row)
        return _pack(names, dirs, paths, self.name)


@dataclass(frozen=True)
class ValueIterationLearner:
    """The alternative the paper mentions ("a reinforcement learning algorithm could have
    been used instead to learn value functions"): value iteration on a local grid.

    Cells of ``resolution`` cover the window; a cell is free when its centre is in the
    local world at least the agent radius from its walls. Each direction's goal cells are
    the free cells near the open edge in its sector. V = 0 on goals, and
    V(s) = min over the 8 neighbours of (step cost + V(s')), no corner cutting, iterated
    to a fixed point; the policy follows the decreasing V from the agent's cell.
    """

    agent_radius: float = 0.3
    resolution: float = 0.5
    margin: float = 0.5
    reach: float = 0.5
    """Goal cells lie at least this fraction of the sensor range (less the margin) from
    the agent, as :class:`AStarLearner`'s exits."""
    name: str = "value-iteration"

    def learn(
        self, templates: NDArray[np.float64], max_range: float, n_directions: int
    ) -> PolicySet:
        names, dirs = compass(n_directions)
        h = self.resolution
        half = int(math.ceil(max_range / h))
        coords = (np.arange(-half, half + 1)) * h
        gx, gy = np.meshgrid(coords, coords)
        centres = np.column_stack([gx.ravel(), gy.ravel()])
        paths: list[list[NDArray[np.float64] | None]] = []
        for ranges in np.asarray(templates, dtype=np.float64):
            world = local_world(ranges, max_range)
            radius = min(self.agent_radius, 0.9 * float(world.clearance(np.zeros(2))))
            free = (world.contains(centres) & (world.clearance(centres) >= radius)).reshape(
                gx.shape
            )
            free[half, half] = True  # the agent's own cell
            angle = np.arctan2(gy, gx)
            dist = np.hypot(gx, gy)
            row: list[NDArray[np.float64] | None] = []
            for u in dirs:
                du = np.abs((angle - math.atan2(u[1], u[0]) + np.pi) % (2 * np.pi) - np.pi)
                goal = (
                    free
                    & (du <= np.pi / n_directions)
                    & (dist >= self.reach * max_range - self.margin - radius)
                )
                row.append(_value_iteration_path(free, goal, half, h) if goal.any() else None)
            paths.append(row)
        return _pack(names, dirs, paths, self.name)


def _value_iteration_path(
    free: NDArray[np.bool_], goal: NDArray[np.bool_], centre: int, h: float
) -> NDArray[np.float64] | None:
    """Bellman iteration to the fixed point, then the greedy path from the centre."""
    v = np.where(goal, 0.0, np.inf)
    moves = [(dy, dx) for dy in (-1, 0, 1) for dx in (-1, 0, 1) if dx or dy]
    pad = np.pad(free, 1, constant_values=False)
    n = free.shape[0]

    def shifted(a: NDArray[Any], dy: int, dx: int, fill: Any) -> NDArray[Any]:
        p = np.pad(a, 1, constant_values=fill)
        return p[1 + dy : 1 + dy + n, 1 + dx : 1 + dx + n]

    allowed = {}
    for dy, dx in moves:
        ok = shifted(free, dy, dx, False) & free
        if dx and dy:  # no corner cutting
            ok &= shifted(free, dy, 0, False) & shifted(free, 0, dx, False)
        allowed[(dy, dx)] = ok
    del pad
    for _ in range(4 * n * n):
        best = v.copy()
        for dy, dx in moves:
            cost = h * (math.sqrt(2) if dx and dy else 1.0)
            cand = np.where(allowed[(dy, dx)], shifted(v, dy, dx, np.inf) + cost, np.inf)
            best = np.minimum(best, cand)
        best[~free] = np.inf
        if np.array_equal(best, v):
            break
        v = best
    if not np.isfinite(v[centre, centre]):
        return None
    y, x = centre, centre
    pts = [(x, y)]
    while v[y, x] > 0:
        options = [
            (v[y + dy, x + dx] + h * (math.sqrt(2) if dx and dy else 1.0), dy, dx)
            for dy, dx in moves
            if allowed[(dy, dx)][y, x]
        ]
        _, dy, dx = min(options)
        y, x = y + dy, x + dx
        pts.append((x, y))
    return (np.array(pts, dtype=np.float64) - centre) * h


@dataclass(frozen=True, eq=False)
class ActionPriors:
    """Action priors (§II-D, after Rosman and Ramamoorthy 2012): with one policy set for
    the whole domain (the compass moves), how often each move was taken, unblocked, in
    each template's contexts during exploration. ``probabilities`` is the Laplace-smoothed
    normalisation of ``counts``; both have shape (n_templates, n_directions)."""

    counts: NDArray[np.float64]
    probabilities: NDArray[np.float64]

    @classmethod
    def from_moves(
        cls,
        template: NDArray[np.int64],
        moves_template_frame: NDArray[np.float64],
        n_templates: int,
        n_directions: int,
        *,
        min_step: float = 0.9,
    ) -> ActionPriors:
        """Count the moves (already turned into each template's frame) by nearest compass
        direction; moves shorter than ``min_step`` (stopped by a wall) are not counted."""
        _, dirs = compass(n_directions)
        m = np.asarray(moves_template_frame, dtype=np.float64)
        length = np.hypot(m[:, 0], m[:, 1])
        ok = length >= min_step
        # products summed elementwise, not by BLAS (whose order is the processor's)
        d = np.argmax((m[ok][:, None, :] * dirs[None]).sum(-1), axis=1)
        counts = np.zeros((n_templates, n_directions))
        np.add.at(counts, (np.asarray(template)[ok], d), 1.0)
        probs = (counts + 1.0) / (counts.sum(1, keepdims=True) + n_directions)
        return cls(counts, probs)
