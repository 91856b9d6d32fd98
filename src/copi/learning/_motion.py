"""A learnt model of what moves (paper §II, learnt like the rest: once, without any
task, from the agent's own exploration; self-supervised: the later readings are the
labels).

What it perceives. At level ``map`` the agent knows the reading the static map alone
would give; a ray that reads nearer by more than :data:`copi.core.EXPLAINED` hit
something that moves. Neighbouring such hits form an arc, fitted by a circle
(:func:`detect_discs`): the moving bodies of one reading. :class:`MotionTracker`
follows them from reading to reading (each body's displacement is what the next reading
says of it) and keeps each one's heading and speed.

What it learns (:func:`learn_motion`). From random walks among moving bodies, each body
followed over three readings in a row gives one example: how far it could go ahead
before a wall (from the static map), and how it turned and how fast it went next.
Counted into tables (:class:`MotionModel`), they are the model: P(turn | room ahead)
and P(speed | last speed), and the speed of a body seen once. The turn is learnt in the
body's own frame (its heading is the axis), and every example is counted mirrored too:
the symmetry group of §II-C acting on motion, so that one table serves every heading
and both turning senses.

What it predicts (:func:`sample_motion`). Futures of every body made out, as samples:
each step a turn drawn from the table of the room ahead, a speed from the last one's, a
move that a wall stops. The planner of ``copi-predictive`` plans over them
(:class:`copi.online.PredictiveAgent`). On held-out walks the mean of the samples is
nearer the body's later places than the constant-velocity guess from the last two
readings (:attr:`MotionModel.stats`, and a test against the simulator's own record).

Nothing in it is told the simulator's rule (a heading turning by N(0, 0.6), a speed of
its family, a random new heading at a wall): the tables are what the readings showed.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numba import njit
from numpy.typing import NDArray

from copi._validation import positive_int
from copi.errors import InvalidArgumentError
from copi.geometry.kernels import local_segments, point_segment_d2, sweep_one
from copi.learning._tracking import MAD, MotionTracker
from copi.world import RandomWalk, RangeSensor, Simulator, random_world, sample_world

__all__ = [
    "AHEAD_EDGES",
    "MOTION_MEMBERS",
    "MotionModel",
    "N_TURN",
    "SPEED_EDGES",
    "learn_motion",
    "motion_arrays",
    "motion_errors",
    "motion_from",
    "motion_tables",
    "sample_motion",
]

N_TURN = 36
"""Bins of a turn in [-pi, pi] (10 degrees each)."""
SPEED_EDGES = np.linspace(0.0, 1.6, 17)
"""Bins of a speed, agent steps per step (a body seen faster is in the last)."""
AHEAD_EDGES = np.array([0.0, 0.8, 1.6, 3.2, np.inf])
"""Bins of the room ahead of a body before a wall, agent steps: the context of a turn."""
GATE = 1.6
"""Farthest a body is taken to have moved in one step when it is followed with no model
(learning): the fastest body, 1, and what a fit may be off by."""


def _wrap(a: float) -> float:
    return (a + math.pi) % (2 * math.pi) - math.pi


def _bin(edges: NDArray[np.float64], v: float) -> int:
    i = int(np.searchsorted(edges, v, side="right")) - 1
    return min(max(i, 0), len(edges) - 2)


@dataclass(frozen=True, eq=False)
class MotionModel:
    """What the agent learnt of how things move (see the module): tables of counts,
    Laplace-smoothed when read (:meth:`turn_p`, :meth:`speed_p`, :meth:`start_p`)."""

    turn_counts: NDArray[np.float64]
    """(len(AHEAD_EDGES) - 1, N_TURN): turns seen, by the room ahead before them (each
    example counted twice, as seen and mirrored)."""
    speed_counts: NDArray[np.float64]
    """(len(SPEED_EDGES) - 1, same): speeds seen, by the speed of the step before."""
    start_counts: NDArray[np.float64]
    """(len(SPEED_EDGES) - 1,): speeds seen at all (a body seen once moves at one)."""
    radius: float
    """Mean radius of the bodies measured well (a body of a short arc is taken for one)."""
    stats: dict[str, Any] = field(default_factory=dict)
    """What learning measured: examples, held-out errors against constant velocity."""

    def turn_p(self, kind: str = "robust") -> NDArray[np.float64]:
        """P(turn bin | room ahead), one row per room bin. ``"empirical"``: the turns as
        counted (Laplace-smoothed). ``"robust"``: each row's core, a normal law of the
        robust spread of its turns (1.4826 times their median absolute value), plus as
        many uniform turns as that row has beyond three spreads *more than* the widest
        room's row (with room to spare nothing makes a body turn sharply: the broad turns
        seen there are the perception's own mistakes, a swapped match or a poor fit, and
        only what walls add beyond them is the bodies' own)."""
        c = self.turn_counts + 0.5
        empirical = c / c.sum(axis=1, keepdims=True)
        if kind == "empirical":
            return empirical
        if kind != "robust":
            raise InvalidArgumentError(f"kind must be robust or empirical; got {kind!r}")
        sd, broad = self.turn_spread()
        base = broad[-1]
        out = np.empty_like(empirical)
        for a in range(len(out)):
            w = max(0.0, broad[a] - base) / (1.0 - base) if base < 1 else 0.0
            cdf = _normal_cdf(_TURN_EDGES / max(sd[a], 1e-3))
            core = np.diff(cdf) / max(cdf[-1] - cdf[0], 1e-12)
            out[a] = (1.0 - w) * core + w / N_TURN
        return out

    def turn_spread(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Per room bin, the robust spread of the turns (radians) and the share of them
        beyond three such spreads."""
        mids = 0.5 * (_TURN_EDGES[:-1] + _TURN_EDGES[1:])
        sd = np.empty(len(self.turn_counts))
        broad = np.empty(len(self.turn_counts))
        order = np.argsort(np.abs(mids))
        for a, row in enumerate(self.turn_counts):
            total = row.sum()
            if total <= 0:
                sd[a], broad[a] = math.pi, 1.0
                continue
            cum = np.cumsum(row[order]) / total
            at = min(int(np.searchsorted(cum, 0.5)), len(cum) - 1)
            med = float(np.abs(mids[order])[at])
            sd[a] = MAD * max(med, 1e-3)
            broad[a] = float(row[np.abs(mids) > 3 * sd[a]].sum() / total)
        return sd, broad

    def priors(self) -> dict[str, float]:
        """What a :class:`MotionTracker` assumes until it has measured its own: the
        median speed of the bodies seen, and the robust turn spread with room to spare."""
        cum = np.cumsum(self.start_p())
        b = min(int(np.searchsorted(cum, 0.5)), len(cum) - 1)
        speed = 0.5 * (SPEED_EDGES[b] + SPEED_EDGES[b + 1])
        return {"speed": float(speed), "turn_sd": float(self.turn_spread()[0][-1])}

    def speed_p(self) -> NDArray[np.float64]:
        c = self.speed_counts + 0.5 * np.eye(len(self.speed_counts)) + 1e-3
        return c / c.sum(axis=1, keepdims=True)

    def start_p(self) -> NDArray[np.float64]:
        c = self.start_counts + 1e-3
        return c / c.sum()

    def mean_speed(self) -> float:
        mids = 0.5 * (SPEED_EDGES[:-1] + SPEED_EDGES[1:])
        return float((self.start_p() * mids).sum())

    def check(self) -> MotionModel:
        """Itself, if its tables have the shapes and values a model has; else one clear
        error (a file holding another is refused on load)."""
        n_a, n_s = len(AHEAD_EDGES) - 1, len(SPEED_EDGES) - 1
        for key, a, shape in (("motion_turn", self.turn_counts, (n_a, N_TURN)),
                              ("motion_speed", self.speed_counts, (n_s, n_s)),
                              ("motion_start", self.start_counts, (n_s,))):  # fmt: skip
            if a.shape != shape:
                raise InvalidArgumentError(f"{key} must have shape {shape}; got {a.shape}")
            if not np.isfinite(a).all() or (a < 0).any() or (a > 1e9).any():
                raise InvalidArgumentError(f"{key} must hold counts in 0 .. 1e9 (finite)")
        if not (math.isfinite(self.radius) and 0.05 <= self.radius <= 5.0):
            raise InvalidArgumentError(
                f"the motion model's radius must be in 0.05 .. 5; got {self.radius!r}"
            )
        return self


_TURN_EDGES = np.linspace(-math.pi, math.pi, N_TURN + 1)


def _walk_examples(
    family: str,
    k: int,
    steps: int,
    seed: int,
    sensor: RangeSensor,
    agent_radius: float,
    tracker_class: type[MotionTracker] = MotionTracker,
) -> tuple[list[tuple[float, float, float, float]], list[float]]:
    """The examples and radii of a random walk of ``steps`` steps in world k of
    ``family`` (see :func:`learn_motion`); its bodies followed by a ``tracker_class``
    (a study's may learn more from the same walk)."""
    rng = np.random.default_rng([seed, k, 11])
    world = random_world(rng) if family == "star" else sample_world(family, rng)
    sim = Simulator.from_world(world, rng, agent_radius=agent_radius, sensor=sensor)
    walk = RandomWalk(seed=rng)
    segs = np.ascontiguousarray(world.segments)

    def ahead(c: NDArray[np.float64], heading: float, r: float) -> float:
        local = local_segments(c[0], c[1], segs, 4.0 + r)
        return float(min(sweep_one(c[0], c[1], math.cos(heading), math.sin(heading), local, r),
                         1e3))  # fmt: skip

    tracker = tracker_class(sensor.n_rays, sensor.max_range, ahead=ahead)

    none = np.zeros((0, 2))
    blocked = False
    for _ in range(steps):
        static = sensor.scan(world, sim.position, none, np.zeros(0))
        tracker.update(sim.ranges, static, sim.position)
        result = sim.step(walk(blocked))
        blocked = result.blocked
        if result.contact:  # start afresh: a walk stuck in a body teaches little
            sim = Simulator.from_world(world, rng, agent_radius=agent_radius, sensor=sensor)
            tracker._tracks = []
    return tracker.examples, tracker._radii


def learn_motion(
    families: Sequence[str] = ("crowd", "star", "polygon", "indoor"),
    worlds: int = 40,
    steps: int = 150,
    *,
    seed: int = 0,
    sensor: RangeSensor | None = None,
    agent_radius: float = 0.3,
    progress: Callable[[int, int], None] | None = None,
) -> MotionModel:
    """The motion model from random walks in ``worlds`` worlds of the ``families`` in
    turn, ``steps`` steps each (world k draws from ``default_rng([seed, k, 11])``, apart
    from exploration's and the probes'): every body followed over three well-measured
    readings is one example (see the module). The held-out errors of the model's
    predictions against constant velocity, on the last fifth of the worlds' examples,
    are in :attr:`MotionModel.stats`."""
    positive_int(worlds, "worlds")
    positive_int(steps, "steps")
    sensor = sensor or RangeSensor()
    examples: list[tuple[float, float, float, float]] = []
    radii: list[float] = []
    for k in range(worlds):
        ex, rs = _walk_examples(families[k % len(families)], k, steps, seed, sensor,
                                agent_radius)  # fmt: skip
        examples += ex
        radii += rs
        if progress is not None:
            progress(k + 1, worlds)
    n_a, n_s = len(AHEAD_EDGES) - 1, len(SPEED_EDGES) - 1
    turn = np.zeros((n_a, N_TURN))
    speed = np.zeros((n_s, n_s))
    start = np.zeros(n_s)
    for room, tn, last, v in examples:
        a = _bin(AHEAD_EDGES, room)
        turn[a, _bin(_TURN_EDGES, tn)] += 1.0
        turn[a, _bin(_TURN_EDGES, -tn)] += 1.0  # mirrored: the same motion seen in a mirror
        speed[_bin(SPEED_EDGES, last), _bin(SPEED_EDGES, v)] += 1.0
        start[_bin(SPEED_EDGES, v)] += 1.0
    radius = float(np.mean(radii)) if radii else 0.75
    stats = {"examples": len(examples), "worlds": worlds, "steps": steps,
             "families": list(families), "radius": radius}  # fmt: skip
    return MotionModel(turn, speed, start, radius, stats).check()


@njit(cache=True, nogil=True)
def _draw(cdf):  # type: ignore[no-untyped-def]
    """A bin drawn from the cumulative law ``cdf`` (one uniform draw)."""
    u = np.random.random()
    b = 0
    while b < cdf.shape[0] - 1 and cdf[b] < u:
        b += 1
    return b


_GUIDE = 256
"""Cells of the guide tables of :func:`_guides` (a power of two: u * _GUIDE is exact)."""


@njit(cache=True, nogil=True)
def _guides(cdf):  # type: ignore[no-untyped-def]
    """For each row a of the cumulative laws ``cdf``, ``out[a, q]``: the first bin whose
    cumulative share is q / _GUIDE or more (the last bin at most). A draw u falls in
    cell q = floor(u * _GUIDE), and every bin before ``out[a, q]`` is below u: the scan
    of :func:`_draw` may start there (a guide table; Devroye 1986, §III.2.4) and ends
    on the same bin, after one or two tests instead of half the row's."""
    n_r, n = cdf.shape
    out = np.empty((n_r, _GUIDE), dtype=np.int64)
    for a in range(n_r):
        b = 0
        for q in range(_GUIDE):
            while b < n - 1 and cdf[a, b] < q / _GUIDE:
                b += 1
            out[a, q] = b
    return out


@njit(cache=True, nogil=True, inline="always")
def _draw_row(cdf, a, guide):  # type: ignore[no-untyped-def]
    """:func:`_draw` from row ``a`` of ``cdf``, its scan started by ``guide``
    (:func:`_guides`): the same bin for the same uniform draw."""
    u = np.random.random()
    b = guide[a, int(u * _GUIDE)]
    while b < cdf.shape[1] - 1 and cdf[a, b] < u:
        b += 1
    return b


@njit(cache=True, nogil=True, inline="always")
def _walls_near(x, y, segs, reach, buf):  # type: ignore[no-untyped-def]
    """Copies the walls ``segs`` within ``reach`` of (x, y) into the first rows of
    ``buf``; returns how many (:func:`copi.geometry.kernels.local_segments`, into a
    buffer kept for the whole draw rather than two new arrays)."""
    n = 0
    r2 = reach * reach
    for k in range(segs.shape[0]):
        if point_segment_d2(x, y, segs, k) <= r2:
            for c in range(4):
                buf[n, c] = segs[k, c]
            n += 1
    return n


@njit(cache=True, nogil=True)
def _edge_bin(edges, v):  # type: ignore[no-untyped-def]
    """The bin of ``edges`` holding ``v`` (the first below its lower edge, the last
    above its upper one)."""
    a = 0
    while a < edges.shape[0] - 2 and v >= edges[a + 1]:
        a += 1
    return a


@njit(cache=True, nogil=True)
def _speed_in(speed_edges, b):  # type: ignore[no-untyped-def]
    """A speed uniform in bin ``b`` of ``speed_edges`` (one uniform draw)."""
    return speed_edges[b] + np.random.random() * (speed_edges[b + 1] - speed_edges[b])


@njit(cache=True, nogil=True)  # nogil: many agents draw at once in threads
def sample_motion(  # type: ignore[no-untyped-def]
    bodies, segs, n_samples, horizon, seed, turn_cdf, speed_cdf, start_cdf, ahead_edges,
    speed_edges, clear, cx0, cy0, ch,
):
    """``n_samples`` futures of the ``bodies`` (rows x, y, heading, known, speed, radius:
    :meth:`MotionTracker.rows`) over ``horizon`` steps, drawn from the learnt tables:
    each step a body turns by a draw of the turn table of the room ahead of it (the
    distance it could go along its heading before a wall, binned by ``ahead_edges``),
    takes a speed drawn after its last one, and moves, a wall stopping it. A body whose
    heading is unknown starts at a uniform heading and a speed drawn from ``start_cdf``.
    A seventh column, where ``bodies`` has one, names for each body a row of
    ``turn_cdf`` its first turn is drawn from instead of the room's (-1: the room's):
    a law of how far a heading measured so may be off.

    ``*_cdf``: cumulative tables (rows of the conditional laws); ``clear``: the distance
    to the walls on a grid (origin cx0, cy0, side ch), which spares the swept test of a
    body far from every wall. Returns (n_samples, horizon + 1, d, 2)."""
    np.random.seed(seed)
    d = bodies.shape[0]
    n_turn = turn_cdf.shape[1]
    cny, cnx = clear.shape
    slack = ch * 0.7072
    out = np.empty((n_samples, horizon + 1, d, 2))
    width = 2.0 * math.pi / n_turn
    guide = _guides(turn_cdf)
    # A wall counts for a step only within ``reach`` of the body: farther than the last
    # bin's edge of the room ahead (beyond it every room falls in that bin) and than a
    # step (what may stop the move), so each sweep tests the few walls that can change
    # what it decides, and the futures are the same to the bit as with every wall.
    room_far = ahead_edges[ahead_edges.shape[0] - 2]
    buf = np.empty((segs.shape[0], 4))
    for k in range(d):
        x0 = bodies[k, 0]
        y0 = bodies[k, 1]
        rk = bodies[k, 5]
        known = bodies[k, 3] > 0.5
        first = int(bodies[k, 6]) if bodies.shape[1] > 6 and known else -1
        vmax = max(speed_edges[-1], bodies[k, 4]) if known else speed_edges[-1]
        reach = max(room_far, vmax) + rk + 1e-3
        around = local_segments(x0, y0, segs, horizon * vmax + reach)
        for s in range(n_samples):
            x = x0
            y = y0
            if known:
                h = bodies[k, 2]
                v = bodies[k, 4]
            else:
                h = 2.0 * math.pi * np.random.random()
                v = _speed_in(speed_edges, _draw(start_cdf))
            out[s, 0, k, 0] = x
            out[s, 0, k, 1] = y
            for t in range(horizon):
                ci = int(math.floor((y - cy0) / ch + 0.5))
                cj = int(math.floor((x - cx0) / ch + 0.5))
                # how far every wall is at least (the grid's cell centre's clearance, less
                # the most a point of the cell can be nearer)
                far = clear[ci, cj] - slack if 0 <= ci < cny and 0 <= cj < cnx else -1.0
                n_near = 0 if far > reach else _walls_near(x, y, around, reach, buf)
                local = buf[:n_near]
                room = 1e3
                if not far > room_far + rk:
                    room = sweep_one(x, y, math.cos(h), math.sin(h), local, rk)
                a = _edge_bin(ahead_edges, room)
                row = first if t == 0 and first >= 0 else a
                h += -math.pi + (_draw_row(turn_cdf, row, guide) + np.random.random()) * width
                if speed_cdf.shape[0] > 1:  # a speed drawn after the last (else: kept)
                    v = _speed_in(speed_edges, _draw(speed_cdf[_edge_bin(speed_edges, v)]))
                dx = math.cos(h)
                dy = math.sin(h)
                if far > rk + v + 1e-3:  # no wall within reach: the sweep would not stop it
                    step = v
                else:
                    go = sweep_one(x, y, dx, dy, local, rk)
                    step = min(v, max(go - 1e-6, 0.0))
                x += step * dx
                y += step * dy
                out[s, t + 1, k, 0] = x
                out[s, t + 1, k, 1] = y
    return out


def motion_errors(
    model: MotionModel | None,
    families: Sequence[str] = ("crowd",),
    worlds: int = 10,
    steps: int = 100,
    *,
    seed: int = 1,
    horizons: Sequence[int] = (1, 3, 5, 10),
    samples: int = 32,
    sensor: RangeSensor | None = None,
    agent_radius: float = 0.3,
    turns: str = "robust",
    speeds: str = "keep",
) -> dict[str, dict[int, float]]:
    """How far the predicted places of the bodies an agent makes out are from where the
    simulator's record puts them ``horizons`` steps later, on random walks of worlds the
    model never saw (``default_rng([seed, k, 13])``): for each body followed with a known
    heading, matched to the true disc nearest its fit (within 0.3), the mean distance of
    the model's sample mean (``"model"``) and of the constant-velocity guess from its
    last two fits (``"constant velocity"``) to the disc's true centre. With ``model``
    None only the constant-velocity guess is scored."""
    sensor = sensor or RangeSensor()
    H = max(horizons)
    errs: dict[str, dict[int, list[float]]] = {
        "model": {h: [] for h in horizons}, "constant velocity": {h: [] for h in horizons}}
    none = np.zeros((0, 2))
    for k in range(worlds):
        rng = np.random.default_rng([seed, k, 13])
        fam = families[k % len(families)]
        world = random_world(rng) if fam == "star" else sample_world(fam, rng)
        sim = Simulator.from_world(world, rng, agent_radius=agent_radius, sensor=sensor,
                                   record=True)  # fmt: skip
        walk = RandomWalk(seed=rng)
        prior = model.priors() if model is not None else {"speed": 0.7, "turn_sd": 1.0}
        tracker = MotionTracker(sensor.n_rays, sensor.max_range, speed=prior["speed"],
                                turn_sd=prior["turn_sd"])  # fmt: skip
        segs = np.ascontiguousarray(world.segments)
        grid = np.zeros((1, 1))
        states: list[tuple[int, NDArray[np.float64], NDArray[np.float64]]] = []
        blocked = False
        for t in range(steps + H):
            static = sensor.scan(world, sim.position, none, np.zeros(0))
            tracker.update(sim.ranges, static, sim.position)
            rows = tracker.bodies()
            if t < steps and len(rows):
                truth = sim.centers.copy()
                states.append((t, rows.copy(), truth))
            blocked = sim.step(walk(blocked)).blocked
        traces = np.asarray(sim.traces)  # (T + 1, d, 2): the record, t = 0 first
        for t, rows, truth in states:
            known = rows[:, 3] > 0.5
            if not known.any():
                continue
            rows = rows[known]
            gap = np.linalg.norm(rows[:, None, :2] - truth[None, :, :], axis=2)
            match = gap.argmin(axis=1)
            ok = gap[np.arange(len(rows)), match] < 0.3
            if not ok.any():
                continue
            rows, match = rows[ok], match[ok]
            if model is not None:
                tables = motion_tables(model, turns=turns, speeds=speeds)
                fut = sample_motion(np.ascontiguousarray(rows), segs, samples, H,  # type: ignore[call-arg]
                                    k * 1000 + t, *tables, grid, 0.0, 0.0, 1.0)  # fmt: skip
                mean = fut.mean(axis=0)
            for h in horizons:
                if t + h >= len(traces):
                    continue
                true = traces[t + h][match]
                vel = rows[:, 4:5] * np.column_stack([np.cos(rows[:, 2]), np.sin(rows[:, 2])])
                cv = rows[:, :2] + h * vel
                errs["constant velocity"][h] += np.linalg.norm(cv - true, axis=1).tolist()
                if model is not None:
                    errs["model"][h] += np.linalg.norm(mean[h] - true, axis=1).tolist()
    return {key: {h: float(np.mean(v)) if v else math.nan for h, v in d.items()}
            for key, d in errs.items() if key != "model" or model is not None}  # fmt: skip


MOTION_MEMBERS = ("motion_turn", "motion_speed", "motion_start")
"""The capabilities file's members of a motion model (its radius and statistics are in
the file's metadata)."""


def motion_arrays(model: MotionModel) -> dict[str, NDArray[np.float64]]:
    """The model's tables as a capabilities file stores them."""
    return {"motion_turn": model.turn_counts, "motion_speed": model.speed_counts,
            "motion_start": model.start_counts}  # fmt: skip


def motion_from(meta: dict[str, Any], arrays: dict[str, NDArray[Any]]) -> MotionModel | None:
    """The model a capabilities file holds (None when it holds none), checked
    (:meth:`MotionModel.check`): a file with part of one, tables of other shapes or
    values, or a radius out of range is refused."""
    present = [k for k in MOTION_MEMBERS if k in arrays]
    entry = meta.get("motion_model")
    if not present and entry is None:
        return None
    if len(present) != len(MOTION_MEMBERS) or not isinstance(entry, dict):
        raise InvalidArgumentError(
            f"the motion model is incomplete (members {present}, metadata "
            f"{'present' if isinstance(entry, dict) else 'missing'})"
        )
    radius = entry.get("radius")
    if not isinstance(radius, int | float) or isinstance(radius, bool):
        raise InvalidArgumentError(f"the motion model's radius must be a number; got {radius!r}")
    stats = entry.get("stats", {})
    return MotionModel(
        np.asarray(arrays["motion_turn"], dtype=np.float64),
        np.asarray(arrays["motion_speed"], dtype=np.float64),
        np.asarray(arrays["motion_start"], dtype=np.float64), float(radius),
        dict(stats) if isinstance(stats, dict) else {},
    ).check()


def _normal_cdf(x: NDArray[np.float64]) -> NDArray[np.float64]:
    from scipy.special import ndtr

    return np.asarray(ndtr(x), dtype=np.float64)


def motion_tables(
    model: MotionModel, *, turns: str = "robust", speeds: str = "keep"
) -> tuple[NDArray[np.float64], ...]:
    """The cumulative tables and edges :func:`sample_motion` takes, in its order: turns
    as :meth:`MotionModel.turn_p` gives them (``turns``), and a body's speed kept from
    step to step (``speeds="keep"``: a row of ones, which the sampler reads so) or drawn
    after the last (``"drawn"``: the learnt table)."""
    if speeds not in ("keep", "drawn"):
        raise InvalidArgumentError(f"speeds must be keep or drawn; got {speeds!r}")
    speed = (np.ones((1, len(SPEED_EDGES) - 1)) if speeds == "keep"
             else np.cumsum(model.speed_p(), axis=1))  # fmt: skip
    return (np.ascontiguousarray(np.cumsum(model.turn_p(turns), axis=1)),
            np.ascontiguousarray(speed),
            np.ascontiguousarray(np.cumsum(model.start_p())), AHEAD_EDGES.copy(),
            SPEED_EDGES.copy())  # fmt: skip
