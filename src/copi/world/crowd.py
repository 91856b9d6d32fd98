"""Many agents among each other: N disc agents in one static world, each an obstacle in
every other's reading.

Each agent is copi's navigation agent (a holonomic disc of radius 0.3 that moves at most
1 agent step a step, stopped exactly by walls) with the ring sensor of 32 rays; its
moving obstacles are the other agents. A contact (two discs closer than the sum of their
radii at some time of the step, both moving linearly) is reported, never prevented, as
in :class:`~copi.world.Simulator`. Each agent has a goal; its *trip* ends at the goal
(success) or at its first contact (collision), and by default it then leaves the world
(its disc is in no reading any more); a steady crowd (``step(..., leave=False)``) keeps
every agent: a new goal on arrival, contacts counted and the trip's outcome kept.

The scans go through a uniform grid of the agents' discs (:mod:`copi.world._crowd_kernels`),
so a step costs about N times the discs near one agent, not N squared; memory is linear
in N (the grid has at most about one cell per agent).

Examples
--------
>>> room = crowd_room(50, 0.1)
>>> crowd = Crowd.draw(room, 50, seed=0)
>>> crowd.ranges.shape, int(crowd.active.sum())
((50, 32), 50)
>>> res = crowd.step(crowd.goals - crowd.positions)
>>> res.contact.shape, crowd.t
((50,), 1)
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from copi._rng import Seed, as_generator
from copi._validation import FloatArray, check_count, positive, positive_int
from copi.errors import InvalidArgumentError
from copi.world import _crowd_kernels as kernels
from copi.world._sensor import RangeSensor
from copi.world._world import World

__all__ = [
    "COLLISION",
    "Crowd",
    "CrowdStep",
    "MAX_AGENTS",
    "GAP_EXACT",
    "MAX_DENSITY",
    "RUNNING",
    "SUCCESS",
    "check_density",
    "crowd_room",
    "place_agents",
]

MAX_AGENTS = 100_000
"""Most agents in one crowd (about 2 KB each in the crowd and its decisions: 200 MB;
more is a typing error, refused before any work)."""
MAX_DENSITY = 2.7
"""Most agents per square agent step: discs of radius 0.3 kept :data:`PLACEMENT_GAP`
apart fit no tighter even packed hexagonally (2.73); random placement gives up well
before (near 1.5, saying how many fitted)."""
PLACEMENT_GAP = 0.05
"""Least gap between two agents' discs, and between a disc and a wall, at the start."""
GAP_EXACT = 1.0
"""A step's gap (:attr:`CrowdStep.gap`) is exact below this (agent steps): a contact is
a gap below 0; a larger gap only says that no agent came nearer."""
_CELL_SPACINGS = 2.0
"""A grid cell's side, in mean distances between agents (sqrt(area / N)): about four
agents a cell (measured: from one to three spacings the scan's cost changes little;
smaller cells cost more to walk through, larger ones hand the scan more discs)."""
_TRIES_PER_AGENT = 200
"""Candidates drawn per agent before placement gives up (random sequential placement
needs a few at moderate density, hundreds near its limit)."""

RUNNING, SUCCESS, COLLISION = kernels.RUNNING, kernels.SUCCESS, kernels.COLLISION
"""A trip's outcome codes (:attr:`Crowd.outcome`); a trip still running at the step
limit is a timeout."""


def crowd_room(agents: int, density: float, *, name: str | None = None) -> World:
    """A square room (walls only) holding ``agents`` at ``density`` agents per square
    agent step: side sqrt(agents / density).

    Examples
    --------
    >>> crowd_room(1000, 0.1).bounds
    (0.0, 0.0, 100.0, 100.0)
    """
    n = positive_int(agents, "agents")
    check_count(n, "agents", MAX_AGENTS)
    d = check_density(density)
    side = math.sqrt(n / d)
    corners = np.array([[0.0, 0.0], [side, 0.0], [side, side], [0.0, side]])
    return World(corners, name=name or f"crowd-room-{n}-d{d:g}")


def check_density(density: Any) -> float:
    """``density`` as a float in (0, :data:`MAX_DENSITY`], else one clear error."""
    d = positive(density, "density")
    if d > MAX_DENSITY:
        raise InvalidArgumentError(
            f"density must be at most {MAX_DENSITY:g} agents per square agent step (no more "
            f"discs of radius 0.3 fit, even packed as tightly as they go); got {d:g}"
        )
    return d


def _free_points(world: World, rng: np.random.Generator, n: int, clear: float) -> FloatArray:
    """``n`` points drawn uniformly in the bounding box, kept where a disc of radius
    ``clear`` fits in the free space (may return fewer)."""
    xmin, ymin, xmax, ymax = world.bounds
    p = np.column_stack([rng.uniform(xmin, xmax, n), rng.uniform(ymin, ymax, n)])
    ok = world.contains(p)
    ok[ok] = world.clearance(p[ok]) >= clear
    return np.ascontiguousarray(p[ok])


def _min_distance(world: World, wanted: float) -> float:
    """A start-goal distance every start can meet: ``wanted``, or 0.4 of the room's
    narrower side in a small room."""
    xmin, ymin, xmax, ymax = world.bounds
    return min(wanted, 0.4 * min(xmax - xmin, ymax - ymin))


def place_agents(
    world: World,
    agents: int,
    seed: Seed = None,
    *,
    radius: float = 0.3,
    min_distance: float = 10.0,
) -> tuple[FloatArray, FloatArray]:
    """Starts (no two discs of ``radius`` closer than :data:`PLACEMENT_GAP`, each that far
    from the walls) and goals (each ``min_distance`` from its start, or 0.4 of the room's
    narrower side in a small room), drawn uniformly from ``seed``.

    Returns
    -------
    starts, goals : ndarray of shape (agents, 2), agent steps

    Raises
    ------
    InvalidArgumentError
        When the agents cannot be placed without overlap (random sequential placement
        gave up after 200 candidates per agent), saying how many fitted.
    """
    n = positive_int(agents, "agents")
    check_count(n, "agents", MAX_AGENTS)
    r = positive(radius, "radius")
    rng = as_generator(seed)
    min_dist = 2 * r + PLACEMENT_GAP
    xmin, ymin, xmax, ymax = world.bounds
    h = max(min_dist, math.sqrt((xmax - xmin) * (ymax - ymin) / n))
    nx = max(1, math.ceil((xmax - xmin) / h))
    ny = max(1, math.ceil((ymax - ymin) / h))
    head = np.full(nx * ny, -1, dtype=np.int64)
    nxt = np.full(n, -1, dtype=np.int64)
    starts = np.empty((n, 2))
    placed, tried = 0, 0
    while placed < n and tried < _TRIES_PER_AGENT * n:
        batch = min(max(4 * (n - placed), 1024), _TRIES_PER_AGENT * n - tried)
        cand = _free_points(world, rng, batch, r + PLACEMENT_GAP)
        placed, _ = kernels.place_discs(cand, starts, placed, n, min_dist, xmin, ymin, h, nx,
                                        ny, head, nxt)  # fmt: skip
        tried += batch  # every candidate drawn counts, looked at or not
    if placed < n:
        raise InvalidArgumentError(
            f"cannot place {n:,} agents of radius {r:g} without overlap in {world.name} "
            f"({world.area:,.0f} square agent steps, {n / world.area:.3g} agents per square "
            f"step): only {placed:,} fitted after {tried:,} tries; lower the density"
        )
    goals = _draw_goals(world, rng, starts, r, _min_distance(world, min_distance))
    return starts, goals


def _draw_goals(
    world: World, rng: np.random.Generator, origins: FloatArray, radius: float, least: float
) -> FloatArray:
    """A goal for each origin: uniform in the free space (a disc fits there), at least
    ``least`` away; redrawn row by row, in order, until every row has one."""
    goals = np.empty_like(origins)
    todo = np.arange(len(origins))
    while len(todo):
        cand = _free_points(world, rng, 2 * len(todo) + 16, radius)
        take = min(len(cand), len(todo))
        rows = todo[:take]
        far = np.hypot(*(cand[:take] - origins[rows]).T) >= least
        goals[rows[far]] = cand[:take][far]
        todo = np.concatenate([rows[~far], todo[take:]])
    return goals


@dataclass(frozen=True)
class CrowdStep:
    """What happened to each agent in one step (arrays of shape (N,); agents out of the
    world read False and inf)."""

    contact: NDArray[np.bool_]
    """It touched another agent during the step."""
    reached: NDArray[np.bool_]
    """Its centre ended within the goal tolerance of its goal."""
    gap: NDArray[np.float64]
    """Least surface distance to another agent over the step, exact below
    :data:`GAP_EXACT`; above, at least that (inf: none near)."""
    blocked: NDArray[np.bool_]
    """A wall stopped it short of its move."""
    left: NDArray[np.bool_]
    """It left the world at the end of this step (its trip ended)."""


class Crowd:
    """Mutable state of N agents among each other in a static world (see the module).

    Use :meth:`draw` to place agents; the constructor stores a given state. After every
    step (and at construction) :attr:`ranges` holds each agent's reading.

    Parameters
    ----------
    world : World
    starts, goals : array_like of shape (N, 2)
        Where each agent starts and where it goes, agent steps.
    seed : int or Generator
        Draws the new goals of a steady crowd.
    agent_radius : float
    sensor : RangeSensor
    goal_tolerance : float
        A goal is reached when the centre ends a step within this distance of it.
    min_distance : float
        A new goal lies at least this far from where it is drawn (or 0.4 of the room's
        narrower side in a small room).
    record_every : int
        Keep the positions every this many steps in :attr:`frames` (0: none).
    cell_size : float, optional
        Side of the grid's cells, agent steps (default: two mean distances between
        agents; never below one).
    """

    def __init__(
        self,
        world: World,
        starts: Any,
        goals: Any,
        *,
        seed: Seed = None,
        agent_radius: float = 0.3,
        sensor: RangeSensor | None = None,
        goal_tolerance: float = 0.5,
        min_distance: float = 10.0,
        record_every: int = 0,
        cell_size: float | None = None,
    ) -> None:
        self.world = world
        self.sensor = sensor or RangeSensor()
        self.radius = positive(agent_radius, "agent_radius")
        self.goal_tolerance = positive(goal_tolerance, "goal_tolerance")
        self.min_distance = _min_distance(world, positive(min_distance, "min_distance"))
        self.rng = as_generator(seed)
        self.positions = _rows(starts, "starts")
        n = len(self.positions)
        check_count(n, "agents", MAX_AGENTS)
        self.goals = _rows(goals, "goals")
        if self.goals.shape != self.positions.shape:
            raise InvalidArgumentError(
                f"goals must have one row per agent ({n}); got {len(self.goals)}"
            )
        self.starts = self.positions.copy()
        self.active = np.ones(n, dtype=np.bool_)
        self.ranges = np.full((n, self.sensor.n_rays), self.sensor.max_range)
        self.t = 0
        self.path_length = np.zeros(n)
        self.contacts = np.zeros(n, dtype=np.int64)
        self.min_gap = np.full(n, np.inf)
        self.outcome = np.zeros(n, dtype=np.int8)
        """Each agent's first trip: :data:`RUNNING`, :data:`SUCCESS` or :data:`COLLISION`."""
        self.ended = np.full(n, -1, dtype=np.int64)
        """The step at which each agent's first trip ended (-1: still running)."""
        self.arrivals = np.zeros(n, dtype=np.int64)
        """Goals reached (more than one only in a steady crowd)."""
        self.trip_length = np.full(n, np.nan)
        """The length of each agent's first trip, once it ended (NaN while it runs)."""
        self.velocities = np.zeros((n, 2))
        """Each agent's displacement over the last step (zero before the first)."""
        xmin, ymin, xmax, ymax = world.bounds
        area = (xmax - xmin) * (ymax - ymin)
        h = float(cell_size) if cell_size is not None else _CELL_SPACINGS * math.sqrt(area / n)
        h = max(h, math.sqrt(area / n))  # at most about one cell per agent: memory linear
        self._grid = (xmin, ymin, h, max(1, math.ceil((xmax - xmin) / h)),
                      max(1, math.ceil((ymax - ymin) / h)))  # fmt: skip
        cells = self._grid[3] * self._grid[4]
        self._cell_of = np.empty(n, dtype=np.int64)
        self._start = np.empty(cells + 1, dtype=np.int64)
        self._items = np.empty(n, dtype=np.int64)
        self._fill = np.empty(cells, dtype=np.int64)
        self._ordered = np.empty((n, 2))
        self._old = np.empty_like(self.positions)
        self._actions = np.empty_like(self.positions)
        self._blocked = np.empty(n, dtype=np.bool_)
        self._gap = np.empty(n)
        self._near = np.empty(n, dtype=np.int64)
        self.record_every = int(record_every)
        self.frames: list[tuple[int, NDArray[np.float32], NDArray[np.bool_]]] = []
        """(t, positions as float32, active) every ``record_every`` steps."""
        self.sense()
        self._record()

    @classmethod
    def draw(
        cls,
        world: World,
        agents: int,
        seed: Seed = None,
        *,
        agent_radius: float = 0.3,
        min_distance: float = 10.0,
        **kwargs: Any,
    ) -> Crowd:
        """Place ``agents`` in ``world`` (:func:`place_agents`) from ``seed``, whose stream
        then draws the new goals of a steady crowd."""
        rng = as_generator(seed)
        starts, goals = place_agents(world, agents, rng, radius=agent_radius,
                                     min_distance=min_distance)  # fmt: skip
        return cls(world, starts, goals, seed=rng, agent_radius=agent_radius,
                   min_distance=min_distance, **kwargs)  # fmt: skip

    @property
    def n_agents(self) -> int:
        return len(self.positions)

    @property
    def nbytes(self) -> int:
        """Bytes of the crowd's arrays (its state, grid and scratch; the frames aside)."""
        return sum(v.nbytes for v in vars(self).values() if isinstance(v, np.ndarray))

    # -- sensing ------------------------------------------------------------------------

    def index(self) -> None:
        """Sort the agents still in the world into the grid (after they moved)."""
        x0, y0, h, nx, ny = self._grid
        kernels.build_grid(self.positions, self.active, x0, y0, h, nx, ny, self._cell_of,
                           self._start, self._items, self._fill, self._ordered)  # fmt: skip

    def scan(self, lo: int = 0, hi: int | None = None) -> None:
        """Readings of the agents ``lo .. hi - 1`` still in the world into :attr:`ranges`
        (the grid must be current: :meth:`index`)."""
        x0, y0, h, nx, ny = self._grid
        s = self.sensor
        kernels.scan_agents(self.positions, self.active, int(lo),
                            self.n_agents if hi is None else int(hi), s.cos, s.sin,
                            self.world.segments, self.radius, s.max_range, x0, y0, h, nx, ny,
                            self._start, self._items, self._ordered, self.ranges)  # fmt: skip

    def sense(self) -> None:
        """:meth:`index`, then every agent's reading."""
        self.index()
        self.scan()

    def static_ranges(self, rows: Any) -> FloatArray:
        """The readings the walls alone give agents ``rows``, shape (len(rows), n_rays)
        (what a method at level ``map`` is told beside its reading)."""
        return self.sensor.scan(self.world, self.positions[np.asarray(rows)].reshape(-1, 2))

    def neighbours(self, b: int, reach: float | None = None) -> NDArray[np.int64]:
        """The agents in the world within ``reach`` (default: the sensor's range plus a
        disc) of agent b's centre, b aside, from the current grid."""
        x0, y0, h, nx, ny = self._grid
        r = self.sensor.max_range + self.radius if reach is None else float(reach)
        k = kernels.within(self.positions, self.active, int(b), r, x0, y0, h, nx, ny,
                           self._start, self._items, self._near)  # fmt: skip
        return self._near[:k].copy()

    # -- one step -----------------------------------------------------------------------

    def step(
        self,
        actions: Any,
        *,
        leave: bool = True,
        sense: bool = True,
        moved: Callable[[], None] | None = None,
    ) -> CrowdStep:
        """Advance one step: every agent in the world moves by its row of ``actions``
        (N, 2) (clipped to norm 1; rows of agents out of the world are ignored), stopped
        by walls; contacts are the closest approaches of the linear moves.

        With ``leave`` an agent whose trip ends (its goal, or a contact) leaves the world;
        without, it stays: a new goal on arrival, contacts only counted. Then the grid is
        rebuilt and every agent still in scans (``sense=False``: the caller scans,
        e.g. in slices).

        ``moved()`` is called as soon as what the next step reads is settled: the
        positions, the goals and who is in the world (:attr:`t` already the new step).
        Without ``leave`` that is before the step's contacts are measured (no agent
        leaves, and a new goal depends on the arrival alone), so that the next step's
        sensing may start while this one's books are kept (:class:`Team` starts its
        other processes there); with ``leave``, after them. Until the call returns,
        the books (contacts, gaps, :attr:`velocities`, the outcomes) are the last
        step's."""
        n = self.n_agents
        a = np.asarray(actions, dtype=np.float64)
        if a.shape != (n, 2):
            raise InvalidArgumentError(f"actions must have shape ({n}, 2); got {a.shape}")
        clipped = self._actions
        bad = kernels.clip_actions(a, self.active, clipped)
        if bad >= 0:
            raise InvalidArgumentError(
                f"actions must be finite; agent {bad}'s is {a[bad].tolist()}"
            )
        x0, y0, h, nx, ny = self._grid
        was = self.active.copy()
        kernels.move_agents(self.positions, clipped, was, self.world.segments, self.radius,
                            self._old, self._blocked)  # fmt: skip
        reached = np.empty(n, dtype=np.bool_)
        kernels.arrived(self.positions, self.goals, was, self.goal_tolerance, reached)
        self.t += 1
        if not leave:
            rows = np.flatnonzero(reached)
            if len(rows):
                self.goals[rows] = _draw_goals(self.world, self.rng, self.positions[rows],
                                               self.radius, self.min_distance)  # fmt: skip
            if moved is not None:
                moved()
        # the grid still holds the positions before the move, as agent_gaps needs
        kernels.agent_gaps(self._old, self.positions, was, self.radius, GAP_EXACT,
                           x0, y0, h, nx, ny, self._start, self._items, self._ordered,
                           self._gap)  # fmt: skip
        gap = self._gap.copy()
        contact = np.empty(n, dtype=np.bool_)
        left = np.empty(n, dtype=np.bool_)
        kernels.account(self.positions, self._old, was, gap, reached, self.t, leave,
                        self.velocities, self.path_length, self.contacts, self.min_gap,
                        self.arrivals, self.outcome, self.ended, self.trip_length,
                        self.active, contact, left)  # fmt: skip
        if leave and moved is not None:
            moved()
        if sense:
            self.sense()
        self._record()
        return CrowdStep(contact=contact, reached=reached, gap=gap,
                         blocked=self._blocked.copy(), left=left)  # fmt: skip

    def _record(self) -> None:
        if self.record_every > 0 and self.t % self.record_every == 0:
            self.frames.append(
                (self.t, self.positions.astype(np.float32), self.active.copy())
            )


def _rows(value: Any, name: str) -> FloatArray:
    try:
        a = np.array(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise InvalidArgumentError(f"{name} must be rows (x, y) of numbers") from None
    if a.ndim != 2 or a.shape[1] != 2 or len(a) == 0:
        raise InvalidArgumentError(f"{name} must have shape (N, 2) with N >= 1; got {a.shape}")
    if not np.isfinite(a).all():
        raise InvalidArgumentError(f"{name} must be finite")
    return np.ascontiguousarray(a)
