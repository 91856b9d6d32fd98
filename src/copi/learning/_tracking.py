"""Perception of what moves, for a ``map``-level agent (:mod:`copi.learning._motion`'s
eyes): the bodies of one reading, fitted by circles, and followed from reading to
reading."""

from __future__ import annotations

import bisect
import math
from collections.abc import Callable
from typing import Any

import numpy as np
from numba import njit
from numpy.typing import NDArray

from copi._validation import check_flag
from copi.core import EXPLAINED
from copi.errors import InvalidArgumentError
from copi.geometry import ring_angles

__all__ = ["HIST", "JOIN", "MAD", "RADII", "WELL", "MotionTracker", "detect_discs", "fit_circle"]

RADII = (0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 1.0)
"""Radii tried on an arc of :data:`WELL` rays or more."""
_RADII = np.array(RADII)
JOIN = 0.8
"""Neighbouring hits farther apart than this belong to different bodies."""
WELL = 3
"""Rays on a body for its fit (and its displacement) to count as measured."""


def fit_circle(
    pts: NDArray[np.float64], r: float, c0: NDArray[np.float64]
) -> tuple[NDArray[np.float64], float]:
    """Centre of the circle of radius ``r`` through ``pts`` (Gauss-Newton from ``c0``) and
    its mean squared residual."""
    p = np.ascontiguousarray(pts, dtype=np.float64)
    c = np.asarray(c0, dtype=np.float64)
    if p.ndim != 2 or p.shape[0] < 1 or p.shape[1] != 2 or c.shape != (2,):
        raise InvalidArgumentError(f"fit_circle needs points of shape (k >= 1, 2) and a start "
                                   f"of shape (2,); got {p.shape} and {c.shape}")  # fmt: skip
    if not (np.isfinite(p).all() and np.isfinite(c).all() and math.isfinite(r) and r > 0):
        raise InvalidArgumentError("fit_circle needs finite points and start and a positive "
                                   f"radius; got radius {r!r}")  # fmt: skip
    cx, cy, err = _fit_circle(p, float(r), float(c[0]), float(c[1]))
    return np.array([cx, cy]), float(err)


@njit(cache=True)
def _fit_circle(pts, r, cx, cy):  # type: ignore[no-untyped-def]
    """Eight Gauss-Newton steps of the fit of :func:`fit_circle`, each the least-squares
    solution of a two-unknown linear system by its normal equations (the least-norm one
    when they are singular: all points on one line through the centre). Written out and
    compiled, because a general solver (numpy's lstsq, scipy's least_squares) costs more
    to call than this whole fit of a few points; a tracker fits every arc with seven
    radii each step."""
    k = pts.shape[0]
    for _ in range(8):
        a11 = 0.0
        a12 = 0.0
        a22 = 0.0
        b1 = 0.0
        b2 = 0.0
        for i in range(k):
            dx = pts[i, 0] - cx
            dy = pts[i, 1] - cy
            n = math.sqrt(dx * dx + dy * dy) + 1e-12
            jx = -dx / n  # the residual's gradient in the centre
            jy = -dy / n
            res = n - r
            a11 += jx * jx
            a12 += jx * jy
            a22 += jy * jy
            b1 -= jx * res
            b2 -= jy * res
        det = a11 * a22 - a12 * a12
        tr = a11 + a22
        if det > 1e-12 * tr * tr:
            sx = (a22 * b1 - a12 * b2) / det
            sy = (a11 * b2 - a12 * b1) / det
        elif tr > 0.0:  # rank one: A = tr u u^T, b along u; the least-norm step
            if a11 >= a22:
                ux, uy = a11, a12
            else:
                ux, uy = a12, a22
            un = math.sqrt(ux * ux + uy * uy)
            ux /= un
            uy /= un
            f = (ux * b1 + uy * b2) / tr
            sx = f * ux
            sy = f * uy
        else:
            break
        cx += sx
        cy += sy
    err = 0.0
    for i in range(k):
        dx = pts[i, 0] - cx
        dy = pts[i, 1] - cy
        e = math.sqrt(dx * dx + dy * dy) - r
        err += e * e
    return cx, cy, err / k


SPLIT_BAD, SPLIT_COST = 0.01, 0.05
"""``split``: an arc whose one circle leaves a mean squared residual above ``SPLIT_BAD``
is cut into the runs of rays that fit circles best, each run costing its squared
residuals plus ``SPLIT_COST`` (a run too short for its own fit, 1.5 times that)."""


@njit(cache=True)
def _piece(hits, s, unit, px, py, radii, short, a, b):  # type: ignore[no-untyped-def]
    """The circle of the rays a..b of an arc (hits, ranges ``s``, directions ``unit``;
    the agent at px, py), fitted as :func:`detect_discs` says: (cx, cy, radius, mean
    squared residual; inf when every fit put the centre before the middle hit).
    Compiled: a tracker fits every arc with seven radii each step."""
    k = b - a + 1
    mid = a + k // 2
    behind = s[mid]
    best_c = (0.0, 0.0)
    best_r = short
    best_e = np.inf
    first = True
    n_r = radii.shape[0] if k >= WELL else 1
    for q in range(n_r):
        r = radii[q] if k >= WELL else short
        c0x = hits[mid, 0] + r * unit[mid, 0]
        c0y = hits[mid, 1] + r * unit[mid, 1]
        if k > 1:
            cx, cy, err = _fit_circle(hits[a : b + 1], r, c0x, c0y)
        else:
            cx, cy, err = c0x, c0y, 0.0
        if math.sqrt((cx - px) ** 2 + (cy - py) ** 2) < behind:
            cx, cy, err = c0x, c0y, np.inf
        if first or err < best_e - 1e-9:
            best_c = (cx, cy)
            best_r = r
            best_e = err
            first = False
    return best_c[0], best_c[1], best_r, best_e


@njit(cache=True)
def _split_arc(hits, s, unit, px, py, radii, short, cost):  # type: ignore[no-untyped-def]
    """The arc's rays cut into runs, one body each, of least total cost (the sum over
    runs of the squared residuals of the run's circle, :func:`_piece`, plus ``cost``;
    1.5 ``cost`` for a run shorter than :data:`WELL`): by dynamic programming over the
    cut points, every run's circle fitted once. Returns rows (first ray, last ray, cx,
    cy, radius). Written out and compiled: an arc of L rays has L (L + 1) / 2 runs, each
    fitted with seven radii."""
    L = hits.shape[0]
    fit = np.empty((L, L, 4))
    for a in range(L):
        for b in range(a, L):
            cx, cy, r, err = _piece(hits, s, unit, px, py, radii, short, a, b)
            fit[a, b, 0] = cx
            fit[a, b, 1] = cy
            fit[a, b, 2] = r
            k = b - a + 1
            sse = err * k if err < np.inf else 1e9
            fit[a, b, 3] = sse + (cost if k >= WELL else 1.5 * cost)
    best = np.full(L + 1, np.inf)
    best[0] = 0.0
    prev = np.zeros(L + 1, dtype=np.int64)
    for b in range(1, L + 1):
        for a in range(b):
            c = best[a] + fit[a, b - 1, 3]
            if c < best[b]:
                best[b] = c
                prev[b] = a
    n = 0
    b = L
    while b > 0:
        n += 1
        b = prev[b]
    out = np.empty((n, 5))
    b = L
    i = n - 1
    while b > 0:
        a = prev[b]
        out[i, 0] = a
        out[i, 1] = b - 1
        out[i, 2:] = fit[a, b - 1, :3]
        i -= 1
        b = a
    return out


def detect_discs(
    ranges: NDArray[np.float64],
    static: NDArray[np.float64],
    position: NDArray[np.float64],
    unit: NDArray[np.float64],
    max_range: float,
    radii_seen: list[float],
    split: bool = False,
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.int64]]:
    """The moving bodies of one reading: centres (k, 2), radii (k,) and the rays on each.

    Hits nearer than the static reading by more than :data:`copi.core.EXPLAINED` form
    arcs of neighbouring rays (less than :data:`JOIN` apart; the arc across ray 0 is
    one). An arc of :data:`WELL` rays or more is fitted by a circle (each radius of
    :data:`RADII` tried, the best fit kept; its radius is appended to ``radii_seen``);
    a shorter one is taken for a body of the mean radius seen so far (0.75 before any)
    behind its middle hit. ``unit``: the rays' directions (n_rays, 2).

    ``split``: an arc of 2 :data:`WELL` - 1 rays or more that one circle fits badly (a
    mean squared residual above :data:`SPLIT_BAD`: discs side by side, their hits less
    than :data:`JOIN` apart) is cut into the runs of rays that circles fit best
    (:data:`SPLIT_COST`), one body each."""
    split = check_flag(split, "split")
    s, st = ranges, static
    n = len(s)
    hits = position + s[:, None] * unit
    idx = np.flatnonzero((s < st - EXPLAINED) & (s < max_range - 1e-9))
    if idx.size == 0:
        return np.zeros((0, 2)), np.zeros(0), np.zeros(0, dtype=np.int64)
    # neighbouring hits join (a ray and the next, less than JOIN apart): the arcs
    step = hits[idx[1:]] - hits[idx[:-1]]
    join = (idx[1:] == idx[:-1] + 1) & (_gaps(step) < JOIN)
    arcs = np.split(idx, np.flatnonzero(~join) + 1)
    if (len(arcs) > 1 and arcs[0][0] == 0 and arcs[-1][-1] == n - 1
            and math.dist(hits[0], hits[n - 1]) < JOIN):  # fmt: skip
        arcs[0] = np.concatenate([arcs.pop(), arcs[0]])  # the arc across ray 0
    centres, radii, rays = [], [], []
    px, py = float(position[0]), float(position[1])
    mean_at = [-1, 0.75]  # (radii seen when their mean was taken, the mean)

    def short() -> float:
        """The mean radius seen so far (0.75 before any): a short arc's body's."""
        k = len(radii_seen)
        if mean_at[0] != k:  # taken again only when a radius came in
            mean_at[0], mean_at[1] = k, float(np.mean(radii_seen)) if k else 0.75
        return mean_at[1]

    for arc in arcs:
        pts = hits[arc]  # finite, (k, 2)
        s_arc = s[arc]
        u_arc = unit[arc]
        k = len(arc)
        # a short arc's body takes the mean radius; a long one's is fitted (no mean needed)
        mean_r = short() if k < WELL or (split and k >= 2 * WELL - 1) else 0.75
        cx, cy, r, err = _piece(pts, s_arc, u_arc, px, py, _RADII, mean_r, 0, k - 1)
        if split and k >= 2 * WELL - 1 and err > SPLIT_BAD:
            runs = _split_arc(pts, s_arc, u_arc, px, py, _RADII, mean_r, SPLIT_COST)
            for a, b, cx, cy, r in runs:
                centres.append((cx, cy))
                radii.append(float(r))
                rays.append(int(b - a + 1))
                if b - a + 1 >= WELL:
                    radii_seen.append(float(r))
            continue
        centres.append((cx, cy))
        radii.append(r)
        rays.append(k)
        if k >= WELL:
            radii_seen.append(r)
    return (np.array(centres, dtype=np.float64).reshape(-1, 2), np.array(radii),
            np.array(rays, dtype=np.int64))  # fmt: skip


def _gaps(d: NDArray[np.float64]) -> NDArray[np.float64]:
    """The lengths of the rows of ``d`` (k, 2), as :func:`math.dist` gives them: numpy's
    hypot, and where it is within a hair of :data:`JOIN` (the two may differ in the last
    bit), math.dist's own, so that an arc is cut where the one-ray-at-a-time loop cut
    it."""
    out = np.hypot(d[:, 0], d[:, 1])
    for i in np.flatnonzero(np.abs(out - JOIN) < 1e-9):
        out[i] = math.hypot(float(d[i, 0]), float(d[i, 1]))
    return out


def _median(ordered: list[float]) -> float:
    """The median of the numbers ``ordered`` (sorted, at least one), as numpy's median
    gives it: the middle one, or the mean of the middle two."""
    k = len(ordered)
    if k % 2:
        return ordered[k // 2]
    return (ordered[k // 2 - 1] + ordered[k // 2]) / 2


HIST = 4
"""Fits a track keeps (its centre in the last readings, oldest first)."""
MIN_SPEED_SAMPLES = 5
MIN_TURN_SAMPLES = 20
MAD = 1.4826
"""Standard deviation over median absolute deviation, for a normal law."""


class MotionTracker:
    """The moving bodies of a ``map``-level agent's readings, followed from step to step.

    Each reading's bodies (:func:`detect_discs`) are matched to the last step's: a body
    moves ``speed`` a step whichever way it turned, so of the last step's bodies one
    ``speed`` away (within 0.5), the nearest to its predicted place first. A body's
    velocity is its displacement's direction at the estimated speed; one matched to
    nothing, or that barely moved (0.2 or less), has velocity zero (its heading unknown).

    ``speed`` is the median displacement of bodies measured well twice running
    (:data:`WELL` rays or more each time), ``turn_sd`` the robust spread (1.4826 times
    the median absolute value) of the heading change between two such displacements in a
    row; until enough have been seen (5 and 20) the priors stand, the values given (a
    learnt :class:`MotionModel` gives its own: :meth:`MotionModel.priors`).

    With ``ahead`` (learning: the room a body has before a wall along its heading, from
    the static map), every body followed over three well-measured readings whose match
    had no other candidate is an example of how bodies move, kept in :attr:`examples`.

    With ``split``, an arc one circle fits badly is cut into several bodies
    (:func:`detect_discs`).

    Examples
    --------
    >>> from copi.world import RangeSensor, World
    >>> room = World([[0, 0], [20, 0], [20, 20], [0, 20]])
    >>> sensor, me = RangeSensor(), np.array([10.0, 10.0])
    >>> static = sensor.scan(room, me, np.zeros((0, 2)), np.zeros(0))
    >>> ranges = sensor.scan(room, me, np.array([[13.0, 10.0]]), np.array([0.8]))
    >>> t = MotionTracker(sensor.n_rays, sensor.max_range)
    >>> centres, radii, rays = t.detect(ranges, static, me)
    >>> np.round(centres, 2).tolist(), np.round(radii, 1).tolist(), rays.tolist()
    ([[13.0, 10.0]], [0.8], [3])
    """

    def __init__(
        self,
        n_rays: int,
        max_range: float,
        *,
        speed: float = 0.7,
        turn_sd: float = 1.0,
        ahead: Callable[[NDArray[np.float64], float, float], float] | None = None,
        split: bool = False,
    ) -> None:
        for key, v in (("speed", speed), ("turn_sd", turn_sd), ("max_range", max_range)):
            if not (isinstance(v, int | float) and math.isfinite(v) and v > 0):
                raise InvalidArgumentError(f"{key} must be a positive number; got {v!r}")
        if int(n_rays) != n_rays or n_rays < 4:
            raise InvalidArgumentError(f"n_rays must be a whole number >= 4; got {n_rays!r}")
        self.n_rays = int(n_rays)
        self.max_range = float(max_range)
        ang = ring_angles(self.n_rays)
        self._unit = np.column_stack([np.cos(ang), np.sin(ang)])
        self.prior_speed = float(speed)
        self.prior_turn_sd = float(turn_sd)
        self.ahead = ahead
        self.split = check_flag(split, "split")
        self._tracks: list[dict[str, Any]] = []
        self._next_id = 0
        # what its tracks measured: displacements, heading changes, radii
        self._speeds: list[float] = []
        self._turns: list[float] = []
        # the same, kept sorted (of the turns, their sizes): a median is read, not sorted
        self._speeds_sorted: list[float] = []
        self._turn_sizes: list[float] = []
        self._radii: list[float] = []
        self._radius = np.zeros(0)
        self.examples: list[tuple[float, float, float, float]] = []
        """(room ahead before the step, turn, last speed, speed) of each body followed
        over three well-measured readings (with ``ahead``; what :func:`learn_motion`
        counts)."""

    @property
    def speed(self) -> float:
        """The bodies' speed per step: estimated once 5 displacements were measured."""
        if len(self._speeds) < MIN_SPEED_SAMPLES:
            return self.prior_speed
        return _median(self._speeds_sorted)

    @property
    def turn_sd(self) -> float:
        """The spread of a body's heading change per step, radians (robust estimate)."""
        if len(self._turns) < MIN_TURN_SAMPLES:
            return self.prior_turn_sd
        return float(MAD * _median(self._turn_sizes))

    def detect(
        self, ranges: NDArray[np.float64], static: NDArray[np.float64], position: Any
    ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.int64]]:
        """The bodies in one reading: centres (k, 2), radii (k,) and the rays on each
        (the radii of well-measured bodies are remembered for the short arcs to come)."""
        s = np.asarray(ranges, dtype=np.float64)
        st = np.asarray(static, dtype=np.float64)
        if s.shape != (self.n_rays,) or st.shape != (self.n_rays,):
            raise InvalidArgumentError(
                f"ranges and static must have shape ({self.n_rays},); got {s.shape} and "
                f"{st.shape}"
            )
        pos = np.asarray(position, dtype=np.float64)
        if pos.shape != (2,) or not np.isfinite(pos).all():
            raise InvalidArgumentError(f"position must be two finite numbers; got {position!r}")
        return detect_discs(s, st, pos, self._unit, self.max_range, self._radii, self.split)

    def update(
        self, ranges: NDArray[np.float64], static: NDArray[np.float64], position: Any
    ) -> NDArray[np.float64]:
        """Follow one more reading; the bodies made out, as rows (x, y, vx, vy, radius)
        (velocity zero: heading unknown), the rows :class:`copi.bounds.ModelOracle` reads
        (:meth:`bodies` gives them as :func:`sample_motion` reads them)."""
        C, R, rays = self.detect(ranges, static, position)
        tracks = self._tracks
        speed = self.speed
        pairs = []
        found = C.tolist()  # math.dist reads Python floats faster than numpy's
        for ti, t in enumerate(tracks):
            cx, cy = t["c"].tolist()
            vx, vy = t["v"].tolist()
            ahead = (cx + vx, cy + vy)
            for di in range(len(C)):
                # a body moves ``speed`` a step, whichever way it turned; of the
                # candidates, the one nearest its prediction (if its heading is known)
                ring = abs(math.dist(found[di], (cx, cy)) - speed)
                if ring < 0.5:
                    near = math.dist(found[di], ahead) if t["known"] else ring
                    pairs.append((near, ti, di))
        pairs.sort()
        # a match is unambiguous when neither of its two had another candidate: only
        # those teach the model (a swapped match reads as a turn that never was)
        per_t = np.bincount([ti for _, ti, _ in pairs], minlength=len(tracks))
        per_d = np.bincount([di for _, _, di in pairs], minlength=len(C))
        used_t: set[int] = set()
        new: list[dict[str, Any] | None] = [None] * len(C)  # a track per detection
        for _, ti, di in self._chosen(pairs, len(tracks), len(C)):
            if ti in used_t or new[di] is not None:
                continue
            used_t.add(ti)
            t = tracks[ti]
            disp = C[di] - t["c"]
            length = math.hypot(disp[0], disp[1])
            # measured: both fits good, and it moved (a heading to speak of)
            measured = rays[di] >= WELL and t["rays"] >= WELL and length > 0.05
            heading = math.atan2(disp[1], disp[0])
            if measured:
                self._speeds.append(length)
                bisect.insort(self._speeds_sorted, length)
                if t["heading"] is not None:
                    turn = (heading - t["heading"] + math.pi) % (2 * math.pi) - math.pi
                    self._turns.append(turn)
                    bisect.insort(self._turn_sizes, abs(turn))
                    if self.ahead is not None and per_t[ti] == 1 and per_d[di] == 1:
                        room = self.ahead(t["c"], t["heading"], float(R[di]))
                        self.examples.append((room, turn, t["length"], length))
            known = length > 0.2
            c = C[di].copy()
            new[di] = {
                "c": c, "rays": int(rays[di]), "known": known,
                "v": disp / length * speed if known else np.zeros(2),
                "heading": heading if measured else None, "length": length,
                "id": t["id"], "hist": [*t["hist"][1 - HIST:], c],
            }  # fmt: skip
        for di in range(len(C)):
            if new[di] is None:  # first seen: heading unknown
                c = C[di].copy()
                new[di] = {"c": c, "rays": int(rays[di]), "known": False,
                           "v": np.zeros(2), "heading": None, "length": 0.0,
                           "id": self._next_id, "hist": [c]}  # fmt: skip
                self._next_id += 1
        self._tracks = [t for t in new if t is not None]
        self._radius = np.asarray(R, dtype=np.float64)
        out = np.zeros((len(C), 5))
        for i, t in enumerate(self._tracks):
            out[i, :2], out[i, 2:4], out[i, 4] = t["c"], t["v"], R[i]
        return out

    def _chosen(
        self, pairs: list[tuple[float, int, int]], n_tracks: int, n_found: int
    ) -> list[tuple[float, int, int]]:
        """The candidate matches (cost, track, body), cheapest first, that :meth:`update`
        takes in turn, each unless its track or body is taken already: all of them
        (nearest first). A study's tracker may choose otherwise
        (studies/predictive_perception.py assigns them globally)."""
        return pairs

    def tracks(self) -> list[tuple[int, NDArray[np.float64], int]]:
        """The bodies of the last reading as tracks, in :meth:`bodies`' order: (its id,
        the same while the body is followed; its last :data:`HIST` fitted centres, (k,
        2), oldest first; the rays on it now)."""
        return [(t["id"], np.array(t["hist"]), t["rays"]) for t in self._tracks]

    def bodies(self) -> NDArray[np.float64]:
        """The bodies of the last reading as :func:`sample_motion` reads them: rows (x, y,
        heading, known, speed, radius), the speed the estimated one."""
        out = np.zeros((len(self._tracks), 6))
        speed = self.speed
        for i, t in enumerate(self._tracks):
            v = t["v"]
            out[i] = (t["c"][0], t["c"][1], math.atan2(v[1], v[0]), float(t["known"]),
                      speed, self._radius[i])  # fmt: skip
        return out
