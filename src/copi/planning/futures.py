"""Planning a disc agent's moves against sampled futures of moving discs: the planner of
the model-predictive oracle (:class:`copi.bounds.ModelOracle`, on futures drawn from the
discs' true motion model), of ``tracked-mpc`` (on the discs it tracks) and of
``copi-predictive`` (:class:`copi.online.PredictiveAgent`, on futures drawn from its
learnt model of what moves). Whatever draws the futures, :class:`FuturesPlanner` values
a window of cells around the agent against them and picks the first move.

Why by hand: each decision searches a window of a few thousand cells over a dozen steps
in each of 32 futures, with the simulator's own tests of walls and contacts; networkx or
Python heaps would be a hundred times slower than these compiled loops.

The tests are the simulator's (:mod:`copi.geometry.kernels`): a move is made only when a
wall does not stop it (``sweep_one``), and it is in contact when the closest approach of
the two linear motions over the step is below the sum of radii (``closest_approach``).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numba import njit
from numpy.typing import NDArray

from copi.errors import InvalidArgumentError
from copi.geometry import clearance
from copi.geometry.kernels import (
    closest_approach,
    escapes,
    free_moves,
    local_segments,
    sweep_one,
)
from copi.planning._field import GoalField, clearance_grid, field_at
from copi.planning._hindsight import covers, disc_cells, hindsight_values
from copi.world import World

__all__ = [
    "FuturesPlanner",
    "MARGIN",
    "PLANS",
    "compass_moves",
    "escape_move",
    "field_at",
    "field_grid",
    "hindsight_values",
    "occupancy",
    "risk_values",
    "window",
]

MARGIN = 1e-6
"""A move must clear every wall and disc by this much more than the simulator demands, so
that rounding (the simulator normalises a command of norm 1 + 1e-16) never turns a
planned move into a contact or a stop."""


def compass_moves(n_dirs: int = 16, speeds: tuple[float, ...] = (1.0, 0.5)) -> tuple[
    NDArray[np.float64], NDArray[np.int64]
]:
    """The moves of the space-time searches: ``n_dirs`` directions at each of ``speeds``,
    and waiting (last). Returns (displacements (m, 2), direction index of each, -1 for
    waiting)."""
    ang = 2 * np.pi * np.arange(n_dirs) / n_dirs
    unit = np.column_stack([np.cos(ang), np.sin(ang)])
    moves = np.vstack([s * unit for s in speeds] + [np.zeros((1, 2))])
    dirs = np.concatenate([np.arange(n_dirs)] * len(speeds) + [np.array([-1])])
    return np.ascontiguousarray(moves), dirs.astype(np.int64)


@njit(cache=True)
def _mark_contacts(samples, s, radii, agent_r, margin, x0, y0, res, blocked):  # type: ignore[no-untyped-def]
    """Sets ``blocked[t, i, j]`` where, in sample ``s`` at step t >= 1, some disc is within
    the sum of radii plus ``margin`` of the centre of window cell (i, j) (origin x0, y0,
    side ``res``); cells already set stay set."""
    horizon = samples.shape[1] - 1
    n = blocked.shape[1]
    for t in range(1, horizon + 1):
        for k in range(samples.shape[2]):
            reach = agent_r + radii[k] + margin
            cx = samples[s, t, k, 0]
            cy = samples[s, t, k, 1]
            i0, i1, j0, j1 = disc_cells(cx, cy, reach, x0, y0, res, 0, n - 1)
            for i in range(i0, i1 + 1):
                for j in range(j0, j1 + 1):
                    if covers(cx, cy, reach, x0, y0, res, i, j):
                        blocked[t, i, j] = True


@njit(cache=True)
def occupancy(samples, radii, agent_r, margin, x0, y0, res, n):  # type: ignore[no-untyped-def]
    """``P[t, i, j]``: the share of samples in which some disc, at step t, is within the
    sum of radii plus ``margin`` of the centre of window cell (i, j) (origin x0, y0, side
    ``res``, n x n cells)."""
    n_s = samples.shape[0]
    horizon = samples.shape[1] - 1
    count = np.zeros((horizon + 1, n, n), dtype=np.int32)
    blocked = np.zeros((horizon + 1, n, n), dtype=np.bool_)
    for s in range(n_s):
        blocked[:] = False
        _mark_contacts(samples, s, radii, agent_r, margin, x0, y0, res, blocked)
        for t in range(1, horizon + 1):
            for i in range(n):
                for j in range(n):
                    count[t, i, j] += blocked[t, i, j]
    out = np.empty((horizon + 1, n, n))
    for t in range(horizon + 1):
        for i in range(n):
            for j in range(n):
                out[t, i, j] = count[t, i, j] / n_s
    return out


@njit(cache=True, inline="always")
def _risk(p):  # type: ignore[no-untyped-def]
    """The cost of a probability of contact: minus the log of surviving it."""
    return -math.log(1.0 - min(p, 0.999))


@njit(cache=True, inline="always")
def _best_move(Vn, cost, i, j, offsets, mid_ok):  # type: ignore[no-untyped-def]
    """The least value of a move from cell (i, j) into the next step's layer: over the
    ``offsets`` that stay in the window and clear of walls (``mid_ok``), ``Vn`` plus
    ``cost`` at the cell reached (inf if none; an infinite ``Vn`` stays infinite)."""
    n = Vn.shape[0]
    best = np.inf
    for o in range(offsets.shape[0]):
        a = i + offsets[o, 0]
        b = j + offsets[o, 1]
        if a < 0 or b < 0 or a >= n or b >= n or not mid_ok[o, i, j]:
            continue
        v = Vn[a, b] + cost[a, b]
        if v < best:
            best = v
    return best


@njit(cache=True)
def risk_values(P, ok, terminal, goal, offsets, mid_ok, weight, discount):  # type: ignore[no-untyped-def]
    """Backward induction over the window. ``cost[t, i, j]`` = one step plus ``weight``
    times ``discount ** (t - 1)`` times the risk of being in cell (i, j) at step t (a
    risk far ahead weighs less: the agent replans before it gets there); ``V[t, i, j]`` =
    the least sum of costs from cell (i, j) at step t to the horizon, plus ``terminal``
    there (0 once in a ``goal`` cell: the episode ends). ``ok[i, j]``: the cell is free of walls;
    ``mid_ok[o, i, j]``: offset o from (i, j) keeps clear of them. Returns (V, cost),
    each (horizon + 1, n, n) (V[0] unused)."""
    horizon = P.shape[0] - 1
    n = P.shape[1]
    cost = np.empty_like(P)
    for t in range(horizon + 1):
        w = weight * discount ** max(t - 1, 0)
        for i in range(n):
            for j in range(n):
                cost[t, i, j] = 1.0 + w * _risk(P[t, i, j])
    V = np.full((horizon + 1, n, n), np.inf)
    V[horizon] = terminal
    for t in range(horizon - 1, 0, -1):
        for i in range(n):
            for j in range(n):
                if goal[i, j]:
                    V[t, i, j] = 0.0
                    continue
                if not ok[i, j]:
                    continue
                V[t, i, j] = _best_move(V[t + 1], cost[t + 1], i, j, offsets, mid_ok)
    return V, cost


@njit(cache=True, inline="always")
def _interp(V, x0, y0, res, x, y):  # type: ignore[no-untyped-def]
    """V at (x, y), bilinear over the finite corners of its window cell (inf if none)."""
    n = V.shape[0]
    fx = (x - x0) / res
    fy = (y - y0) / res
    j = int(math.floor(fx))
    i = int(math.floor(fy))
    u = fx - j
    w = fy - i
    total = 0.0
    mass = 0.0
    for di in range(2):
        for dj in range(2):
            a = i + di
            b = j + dj
            if a < 0 or b < 0 or a >= n or b >= n:
                continue
            v = V[a, b]
            if not math.isfinite(v):
                continue
            c = (w if di else 1.0 - w) * (u if dj else 1.0 - u)
            total += c * v
            mass += c
    if mass <= 1e-9:
        return np.inf
    return total / mass


@njit(cache=True)
def _moves_clear(free, offsets, ny, nx):  # type: ignore[no-untyped-def]
    """``out[o, i, j]``: the move ``offsets[o]`` from cell (i, j) of an ny x nx grid is
    clear of walls at its start and its four quarter points, on the grid ``free`` four
    times as fine."""
    out = np.zeros((offsets.shape[0], ny, nx), dtype=np.bool_)
    for o in range(offsets.shape[0]):
        di = offsets[o, 0]
        dj = offsets[o, 1]
        for i in range(ny):
            for j in range(nx):
                good = free[4 * i, 4 * j]
                for frac in range(1, 5):  # quarter points of the move, in fine cells
                    a = 4 * i + di * frac
                    b = 4 * j + dj * frac
                    if not good or a < 0 or b < 0 or a >= 4 * ny or b >= 4 * nx:
                        good = False
                        break
                    good = free[a, b]
                out[o, i, j] = good
    return out


@njit(cache=True)
def field_grid(dist, fx0, fy0, fh, x0, y0, res, ny, nx, gx, gy):  # type: ignore[no-untyped-def]
    """The field's distance to go at the centres of an ny x nx grid (origin x0, y0)."""
    out = np.empty((ny, nx))
    for i in range(ny):
        for j in range(nx):
            out[i, j] = field_at(dist, fx0, fy0, fh, x0 + j * res, y0 + i * res, gx, gy)
    return out


@njit(cache=True, nogil=True)  # nogil: many agents plan at once in threads
def window(ok, mid_ok, terminal, goal, i0, j0, n):  # type: ignore[no-untyped-def]
    """The n x n window of the episode's grids whose corner cell is (i0, j0); cells off
    the grids are walls."""
    ny, nx = ok.shape
    n_off = mid_ok.shape[0]
    w_ok = np.zeros((n, n), dtype=np.bool_)
    w_mid = np.zeros((n_off, n, n), dtype=np.bool_)
    w_term = np.full((n, n), np.inf)
    w_goal = np.zeros((n, n), dtype=np.bool_)
    for a in range(n):
        i = i0 + a
        if i < 0 or i >= ny:
            continue
        for b in range(n):
            j = j0 + b
            if j < 0 or j >= nx:
                continue
            w_ok[a, b] = ok[i, j]
            w_term[a, b] = terminal[i, j]
            w_goal[a, b] = goal[i, j]
            for o in range(n_off):
                w_mid[o, a, b] = mid_ok[o, i, j]
    return w_ok, w_mid, w_term, w_goal




@njit(cache=True, nogil=True)  # nogil: many agents plan at once in threads
def escape_move(  # type: ignore[no-untyped-def]
    px, py, gx, gy, tol, r, segs, samples, radii, moves, margin, escape_margin, V, x0, y0,
    res, loss, dist, fx0, fy0, fh, extra, costs, lost_share,
):
    """The first move of least expected cost, counting as lost each sample in which the
    move is in contact, or leaves no second move clear of that sample's next step by
    ``escape_margin`` more (the agent, replanning, sees where the discs went but not yet
    where they go next: the margin stands for that). Cost: ``loss`` times the share
    lost, plus one step, plus the window's value ``V`` (step 1) after the move, plus
    ``extra[m]`` (a cost of the move's own: zeros for the oracle); each move's cost goes
    into ``costs[m]`` (inf for one a wall stops) and the share of samples it is lost in
    into ``lost_share[m]`` (NaN for one a wall stops). Returns (move, cost, share of samples the
    move is in contact with)."""
    n_s = samples.shape[0]
    d = samples.shape[2]
    n_m = moves.shape[0]
    near = np.empty(d, dtype=np.int64)
    n_near = 0
    for k in range(d):
        ex = samples[0, 0, k, 0] - px
        ey = samples[0, 0, k, 1] - py
        far = 2.0 + 2.0 * 1.0 + r + radii[k] + margin + escape_margin
        if ex * ex + ey * ey <= far * far:
            near[n_near] = k
            n_near += 1
    local = local_segments(px, py, segs, 2.0 + r + 1e-3)
    free2 = np.zeros(n_m, dtype=np.bool_)
    best = -1
    best_cost = np.inf
    best_hit = 1.0
    for m in range(n_m):
        costs[m] = np.inf
        lost_share[m] = np.nan
        dx = moves[m, 0]
        dy = moves[m, 1]
        length = math.sqrt(dx * dx + dy * dy)
        swept = sweep_one(px, py, dx / length, dy / length, local, r) if length > 0.0 else 0.0
        if length > 0.0 and swept < length + MARGIN:
            continue
        qx = px + dx
        qy = py + dy
        done = math.sqrt((qx - gx) ** 2 + (qy - gy) ** 2) <= tol - MARGIN
        free_moves(qx, qy, r, local, moves, free2, MARGIN)  # second moves walls let through
        lost = 0
        hits = 0
        for s in range(n_s):
            hit = False
            for a in range(n_near):
                k = near[a]
                cx = samples[s, 0, k, 0]
                cy = samples[s, 0, k, 1]
                gap = closest_approach(px, py, dx, dy, cx, cy, samples[s, 1, k, 0] - cx,
                                        samples[s, 1, k, 1] - cy)  # fmt: skip
                if gap - r - radii[k] < margin:
                    hit = True
                    break
            if hit:
                hits += 1
                lost += 1
                continue
            if done:
                continue
            if not escapes(qx, qy, r, moves, free2, samples[s, 1], samples[s, 2], radii, near,
                           n_near, margin + escape_margin):  # fmt: skip
                lost += 1
        lost_share[m] = lost / n_s
        cost = loss * lost / n_s + 1.0 + extra[m]
        if not done:
            v = _interp(V[1], x0, y0, res, qx, qy)
            if not math.isfinite(v):
                v = samples.shape[1] - 2 + field_at(dist, fx0, fy0, fh, qx, qy, gx, gy)
            cost += v
        costs[m] = cost
        if cost < best_cost:
            best = m
            best_cost = cost
            best_hit = hits / n_s
    return best, best_cost, best_hit


# Grid moves of the backward induction (in cells of ``RES`` = 0.5: length 0, 0.5, 0.71 and
# 1 agent step), and for each, the fractions of the way at which it is checked for walls.
OFFSETS = np.array(
    [(0, 0), (1, 0), (-1, 0), (0, 1), (0, -1), (1, 1), (1, -1), (-1, 1), (-1, -1),
     (2, 0), (-2, 0), (0, 2), (0, -2)], dtype=np.int64,
)  # fmt: skip
RES = 0.5
OPEN_CAP = 6.0
"""How far :meth:`FuturesPlanner.reset_open` measures the clearance of walls (steps)."""
PLANS = ("hindsight", "mean", "greedy")
"""How :class:`FuturesPlanner` values the window's cells (see it)."""


class FuturesPlanner:
    """The next move of a disc agent against sampled futures of moving discs.

    On a window of 0.5-step cells around the agent it values every cell by *hindsight
    optimisation* (Chong, Givan & Chang 2000; Yoon et al. 2008; ``plan="hindsight"``):
    in each sampled future, solved as if it were known, the least number of steps
    through cells clear of every disc (the sum of radii plus ``margin``) to the goal or to
    the horizon, plus the distance to go around the walls from there (a future with no
    way through costs the horizon, the farthest distance to go and ``loss``); the cell's
    value is the mean over the futures. The move (16 directions at full and half speed,
    or waiting) minimises ``loss`` times the share of futures in which it is lost (in
    contact on the first step, by the simulator's closest-approach test, or with no
    second move clear of that future's next step by ``escape`` more) plus one step plus
    the value of the cell it reaches, plus a cost of the move's own when one is given.

    ``together`` > 1 values that many futures as one in the hindsight: every disc of
    each is in the one solve, so a cell's way must clear all of them, as a plan the agent
    commits to before it can tell those futures apart would (fewer solves, and less
    clairvoyant; the first move's check still counts each future alone).

    ``plan="mean"`` values cells against the mean occupancy instead (each cell entered
    costing ``risk`` times minus the log of surviving it, the future ``discount``-ed);
    ``plan="greedy"`` looks no further than the first move's check (a cell's value is its
    distance to go around the walls). :class:`copi.bounds.ModelOracle` documents what
    each is worth.

    :meth:`reset` builds the episode's grids (walls on a grid twice as fine as the
    window's, the distance to the goal around them: :class:`GoalField`); :meth:`plan`
    takes the futures, drawn by whoever plans: ``samples[s, t, k]`` = (x, y) of disc k
    at step t of future s (t = 0: now).
    """

    def __init__(
        self,
        *,
        horizon: int = 14,
        plan: str = "hindsight",
        risk: float = 10.0,
        loss: float = 200.0,
        discount: float = 0.3,
        margin: float = 0.1,
        escape: float = 0.1,
        together: int = 1,
    ) -> None:
        if int(together) != together or not 1 <= together <= 64:
            raise InvalidArgumentError(f"together must be a whole number in 1 .. 64; got "
                                       f"{together!r}")  # fmt: skip
        if int(horizon) != horizon or not 2 <= horizon <= 40:
            raise InvalidArgumentError(
                f"horizon must be a whole number in 2 .. 40; got {horizon!r}"
            )
        if plan not in PLANS:
            raise InvalidArgumentError(f"plan must be one of {', '.join(PLANS)}; got {plan!r}")
        if not (isinstance(discount, int | float) and 0 < discount <= 1):
            raise InvalidArgumentError(f"discount must be a number in (0, 1]; got {discount!r}")
        for key, v in (("risk", risk), ("loss", loss), ("margin", margin), ("escape", escape)):
            if not (isinstance(v, int | float) and math.isfinite(v) and 0 <= v <= 1e4):
                raise InvalidArgumentError(f"{key} must be a number in [0, 10000]; got {v!r}")
        self.horizon = int(horizon)
        self.plan_kind = plan
        self.risk = float(risk)
        self.loss = float(loss)
        self.discount = float(discount)
        self.margin = float(margin)
        self.escape = float(escape)
        self.together = int(together)
        self.moves, _ = compass_moves()
        self.no_cost = np.zeros(len(self.moves))
        self.costs = np.full(len(self.moves), np.inf)
        """Each move's expected cost at the last plan (inf: a wall stops it), steps."""
        self.lost = np.full(len(self.moves), np.nan)
        """Each move's share of futures lost at the last plan (in contact on its step, or
        with no second move clear: NaN where a wall stops it)."""
        # the window: as far as the horizon's steps go (greedy: the first move's reach)
        self.half = (int(math.ceil(self.horizon / RES)) if plan != "greedy" else 2) + 1

    @property
    def steps(self) -> int:
        """The steps of the futures the plan looks at (the greedy plan: the first two)."""
        return 2 if self.plan_kind == "greedy" else self.horizon

    def reset(self, world: World, goal: NDArray[np.float64], radius: float,
              tolerance: float) -> None:  # fmt: skip
        """The episode's grids, for an agent of ``radius`` going to ``goal``."""
        goal = np.asarray(goal, dtype=np.float64)
        self._grids(world.segments, GoalField(world, goal, float(radius)), world.contains,
                    goal, radius, tolerance)  # fmt: skip

    def reset_open(self, segments: NDArray[np.float64], centre: NDArray[np.float64],
                   goal: NDArray[np.float64], radius: float, tolerance: float) -> None:  # fmt: skip
        """The grids of a world known only by the walls ``segments`` (level ``sensor``:
        the walls the agent sees), for one plan from ``centre``: a box just holding the
        window around it, whose unknown space is free and whose edges lead straight on
        to ``goal`` (:meth:`GoalField.open`). Clearances are kept up to ``OPEN_CAP``
        only (beyond it, the futures' bodies test the walls themselves)."""
        segs = np.ascontiguousarray(np.asarray(segments, dtype=np.float64).reshape(-1, 4))
        n = 2 * (self.half + 3)  # window cells across, and a margin
        x0, y0 = np.asarray(centre, dtype=np.float64) - (self.half + 3) * RES
        fine = RES / 4
        clear = clearance_grid(segs, x0, y0, fine, 4 * n, 4 * n, OPEN_CAP)
        goal = np.asarray(goal, dtype=np.float64)
        field = GoalField.open(clear[::4, ::4], x0, y0, RES, goal, float(radius))
        self._grids(segs, field, None, goal, radius, tolerance, clear=clear)

    def _grids(self, segs: NDArray[np.float64], field: GoalField, contains: Any,
               goal: NDArray[np.float64], radius: float, tolerance: float,
               clear: NDArray[np.float64] | None = None) -> None:  # fmt: skip
        self.r = float(radius)
        self.tol = float(tolerance)
        self.goal = goal.copy()
        self.segs = np.ascontiguousarray(segs)
        self.field = f = field
        # The episode's grids: cells of RES from the field's origin; walls checked on a
        # grid twice as fine (cell centres, midpoints, quarter points of every move).
        fine = RES / 4
        if clear is None:
            ny = int(f.dist.shape[0] * f.h / RES) + 2
            nx = int(f.dist.shape[1] * f.h / RES) + 2
            fy, fx = np.mgrid[0 : 4 * ny, 0 : 4 * nx]
            pts = np.column_stack([f.x0 + fine * fx.ravel(), f.y0 + fine * fy.ravel()])
            clear = np.where(contains(pts), clearance(pts, self.segs), 0.0)
            clear = clear.reshape(4 * ny, 4 * nx)
        ny, nx = clear.shape[0] // 4, clear.shape[1] // 4
        self.clear = np.ascontiguousarray(clear)
        self.fine = fine
        free = clear >= self.r
        ii, jj = np.mgrid[0:ny, 0:nx]
        self.ok = free[4 * ii, 4 * jj]
        self.mid_ok = _moves_clear(free, OFFSETS, ny, nx)
        self.terminal = field_grid(f.dist, f.x0, f.y0, f.h, f.x0, f.y0, RES, ny, nx,
                                   self.goal[0], self.goal[1])  # fmt: skip
        cy = f.y0 + RES * ii
        cx = f.x0 + RES * jj
        self.goal_cells = np.hypot(cx - self.goal[0], cy - self.goal[1]) <= self.tol
        self.terminal[self.goal_cells] = 0.0

    def plan(
        self,
        p: NDArray[np.float64],
        samples: NDArray[np.float64],
        radii: NDArray[np.float64],
        extra: NDArray[np.float64] | None = None,
    ) -> tuple[int, float]:
        """The move from ``p`` (an index into :attr:`moves`, -1: none) against the
        futures ``samples`` (S, T + 1, d, 2) of discs of ``radii``, each move costing
        ``extra[m]`` more (steps) when given; and the share of futures the move is in
        contact with on its first step."""
        f = self.field
        n = 2 * self.half + 1
        i0 = int(math.floor((p[1] - f.y0) / RES)) - self.half
        j0 = int(math.floor((p[0] - f.x0) / RES)) - self.half
        wx0 = f.x0 + j0 * RES
        wy0 = f.y0 + i0 * RES
        ok, mid_ok, terminal, goal = window(self.ok, self.mid_ok, self.terminal,
                                            self.goal_cells, i0, j0, n)  # fmt: skip
        if self.plan_kind == "hindsight":
            # a future with no way through: the horizon, the farthest distance to go, lost
            fin = terminal[np.isfinite(terminal)]
            cap = self.horizon + (float(fin.max()) if fin.size else 0.0) + self.loss
            # solved only where the agent can be (the window's centre is its cell; the
            # move's end, read bilinearly, is within 3 cells of it: box 2 keeps 4)
            hs, hr = samples, radii
            g = self.together
            if g > 1 and samples.shape[0] % g == 0 and samples.shape[2] > 0:
                # g futures solved as one: every disc of each, so a way must clear them all
                S, T1, d, _ = samples.shape
                hs = np.ascontiguousarray(samples.reshape(S // g, g, T1, d, 2)
                                          .transpose(0, 2, 1, 3, 4).reshape(S // g, T1, g * d, 2))
                hr = np.ascontiguousarray(np.tile(radii, g))
            V = hindsight_values(hs, hr, self.r, self.margin, wx0, wy0, RES, ok,
                                 terminal, goal, OFFSETS, mid_ok, cap, 2)  # fmt: skip
        elif self.plan_kind == "greedy":
            V = np.stack([terminal, terminal])  # step 1's value: the distance to go
        else:
            # a cell stands for positions up to half a cell from its centre
            P = occupancy(samples, radii, self.r, self.margin + RES / 2, wx0, wy0, RES, n)
            V, _ = risk_values(P, ok, terminal, goal, OFFSETS, mid_ok, self.risk,
                               self.discount)  # fmt: skip
        m, _, risk = escape_move(
            p[0], p[1], self.goal[0], self.goal[1], self.tol, self.r, self.segs, samples,
            radii, self.moves, self.margin, self.escape, V, wx0, wy0, RES, self.loss,
            f.dist, f.x0, f.y0, f.h, self.no_cost if extra is None else extra, self.costs,
            self.lost,
        )  # fmt: skip
        return int(m), float(risk)
