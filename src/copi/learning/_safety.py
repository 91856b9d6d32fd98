"""Learnt action priors for safety (paper §II-D, last paragraph, after its ref. [25]):
counterfactual probes from states visited in task-independent exploration.

From a state of a random walk among moving obstacles, the simulator is copied once per
action (each compass direction, and waiting) and the action is held for ``horizon`` steps
while the obstacles keep moving (all copies see the same obstacle motion). A probe is
*safe* when no moving obstacle touches the agent meanwhile (``label="hold"``, the
default). With ``label="escape"`` the action is taken once and the probe is safe when it
touches nothing and leaves a second move (a compass direction at full or half speed, or
waiting) that passes every obstacle's next step with :data:`ESCAPE_CLEAR` to spare:
the model-predictive oracle's own check of a first move (:mod:`copi.ceilings`), on the
probe's real future. The second label is what a controller that turns needs (holding a direction is
not what it will do), and the oracle with that check alone, planning nothing further,
succeeds in 111 of 200 validation crowd episodes against compass-guard's 86
(``docs/analysis/benchmark.md``).

Two things are learnt from the probes, both task-independent:

* a **safety model**: the probability that a direction is safe given the reading and
  how it changed since the last step, both *turned so that the direction is ray 0*
  (with ``static_aware``, also the reading the static map alone gives, a ``map``-level
  agent's: the closeness block then keeps only the hits it does not explain, what
  moves; at validation the network alone then won 69 of 200 crowd episodes instead
  of 34, but behind the guard no more than without it: ``docs/analysis/benchmark.md``).
  Turning the reading is the symmetry group's rotation acting on the context: one model
  serves every direction (and every mirror image, which the training data includes), so
  a probe in one direction teaches all of them. It is a one-hidden-layer network (16
  ReLU units, :mod:`copi.learning._mlp`) over fixed features of the turned reading,
  learnt the same on every processor; online it is evaluated by a
  compiled kernel (numpy's per-call overhead alone would exceed the decision budget).
* **per-template priors**: each probe's state mapped to its landmark's template, and
  its direction turned by the landmark's symmetry g into the template's frame, counted
  safe or not: P(safe | template, direction), the paper's action prior over contexts.
  The prototype measurements that motivate the finer model (a node or landmark pools
  readings with a disc at 1 and at 2.5) are in the README.
"""

from __future__ import annotations

import copy
import dataclasses
import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
from numba import njit
from numpy.typing import NDArray

from copi.ceilings._kernels import escapes, free_moves, local_segments
from copi.errors import InvalidArgumentError
from copi.learning._mlp import fit_mlp
from copi.learning._policies import compass
from copi.world import RandomWalk, RangeSensor, Simulator, random_world, sample_world

__all__ = [
    "PROBE_LABELS",
    "SafetyModel",
    "feature_block",
    "kernel_net",
    "learn_safety",
    "probe_states",
    "safety_features",
    "ring_features",
    "safety_of",
    "safety_probabilities",
    "template_directions",
]

CAP = 4.0
"""Ranges beyond this (agent steps) count as far: safety is decided nearby."""
DELTA = 1.5
"""Changes of a range between steps are clipped to +-this."""
N_BLOCKS = 4
"""Feature blocks per ray: near range, its change, closeness of what moves, approach when
close."""
EXPLAINED = 0.05
"""A hit within this of the static map's reading is the static map's (a wall): the
guards' test (:mod:`copi.online._kernels`)."""


@njit(cache=True, inline="always")
def _change(r, p):  # type: ignore[no-untyped-def]
    """A range's change since the last step, clipped to +-DELTA."""
    d = r - p
    if d > DELTA:
        return DELTA
    if d < -DELTA:
        return -DELTA
    return d


@njit(cache=True, inline="always")
def _feature(s, prev, static, i, block):  # type: ignore[no-untyped-def]
    r = s[i]
    d = _change(r, prev[i])
    if block == 0:
        return min(r, CAP) / CAP
    if block == 1:
        return d / DELTA
    if block == 2:
        return math.exp(-r) if r < static[i] - EXPLAINED else 0.0
    return min(d, 0.0) / DELTA * math.exp(-0.5 * r)


def feature_block(n_rays: int) -> int:
    """Length of one feature vector (the bias not included)."""
    return N_BLOCKS * n_rays


@njit(cache=True)
def _features_into(s, prev, static, shift, mirror, out):  # type: ignore[no-untyped-def]
    n = s.shape[0]
    for b in range(N_BLOCKS):
        for j in range(n):
            i = (shift - j) % n if mirror else (shift + j) % n
            out[b * n + j] = _feature(s, prev, static, i, b)


def safety_features(
    s: NDArray[np.float64],
    prev: NDArray[np.float64],
    shift: int,
    mirror: bool = False,
    static: NDArray[np.float64] | None = None,
) -> NDArray[np.float64]:
    """The feature vector of reading ``s`` (previous reading ``prev``; ``static``, the
    reading the static map alone would give, none by default) turned so that ray
    ``shift`` is ray 0 (and mirrored about it with ``mirror``)."""
    s = np.asarray(s, np.float64)
    st = np.full(s.shape, np.inf) if static is None else np.asarray(static, np.float64)
    out = np.empty(feature_block(s.shape[0]))
    _features_into(s, np.asarray(prev, np.float64), st, int(shift), bool(mirror), out)
    return out


@njit(cache=True)
def ring_features(s, prev, static, feat):  # type: ignore[no-untyped-def]
    """The feature blocks of reading ``s`` after ``prev`` (``static``: the static map's
    reading, inf where unknown) into ``feat`` (8 n_rays), each block written twice, so
    that turning the reading is a slice (see :func:`safety_of`). The values are
    :func:`_feature`'s, computed a ray at a time (the change once, not once a block; the
    closeness block's exponential once for a run of equal ranges; the approach block's
    only for a ray that came nearer: otherwise the block is exactly 0)."""
    n = s.shape[0]
    last = np.nan  # the last range whose exponential was taken (rays at the sensor's
    e = 0.0  # reach often repeat one value)
    for i in range(n):
        r = s[i]
        d = _change(r, prev[i])
        v0 = min(r, CAP) / CAP
        v1 = d / DELTA
        if r != last:
            e = math.exp(-r)
            last = r
        v2 = e if r < static[i] - EXPLAINED else 0.0
        v3 = min(d, 0.0) / DELTA  # +-0 unless the ray came nearer (the sign kept)
        if d < 0.0:
            v3 = v3 * math.exp(-0.5 * r)
        feat[i] = v0
        feat[n + i] = v0
        feat[2 * n + i] = v1
        feat[3 * n + i] = v1
        feat[4 * n + i] = v2
        feat[5 * n + i] = v2
        feat[6 * n + i] = v3
        feat[7 * n + i] = v3


def kernel_net(net: NDArray[np.float64]) -> NDArray[np.float64]:
    """The networks ``net`` (2, h + 1, 1 + 4 n_rays), as :class:`SafetyModel` holds them,
    laid out for the kernels: (2, 4 n_rays + 3, h), row 0 the hidden biases, row 1 + i
    every hidden unit's weight of feature i, row 4 n_rays + 1 the output weights, and
    [4 n_rays + 2, 0] the output bias. Feature-major, so that one feature updates every
    hidden unit at once: the loop over units vectorises while each unit's sum keeps its
    order (bias, then the features in turn) on every processor."""
    net = np.asarray(net, dtype=np.float64)
    k, h1, f1 = net.shape
    h = h1 - 1
    out = np.zeros((k, f1 + 2, h))
    out[:, :f1, :] = net[:, :h, :].transpose(0, 2, 1)
    out[:, f1, :] = net[:, h, 1 : 1 + h]
    out[:, f1 + 1, 0] = net[:, h, 0]
    return np.ascontiguousarray(out)


@njit(cache=True)
def safety_of(net_t, k, shift, feat, n):  # type: ignore[no-untyped-def]
    """P(safe) by network ``k`` of ``net_t`` (:func:`kernel_net`; 0: a move along ray 0,
    1: waiting) of the features in ``feat`` (:func:`ring_features`) turned by ``shift``
    rays. No fastmath: every sum runs in the order written, the same on every processor."""
    h = net_t.shape[2]
    last = net_t.shape[1] - 2
    z = net_t[k, 0].copy()
    for b in range(N_BLOCKS):
        w0 = 1 + b * n
        f0 = 2 * b * n + shift
        for j in range(n):
            f = feat[f0 + j]
            row = net_t[k, w0 + j]
            for u in range(h):
                z[u] += row[u] * f
    z2 = net_t[k, last + 1, 0]
    out_w = net_t[k, last]
    for u in range(h):
        if z[u] > 0.0:
            z2 += out_w[u] * z[u]
    return 1.0 / (1.0 + math.exp(-z2))


@njit(cache=True)
def safety_probabilities(s, prev, static, net_t, n_dir, feat, out):  # type: ignore[no-untyped-def]
    """P(safe) of each of ``n_dir`` compass directions (out[:n_dir]) and of waiting
    (out[n_dir]) for reading ``s`` after ``prev`` (``static``: the static map's reading,
    inf where unknown).

    ``net_t``: :func:`kernel_net` of the direction model and the wait model
    (:attr:`SafetyModel.net`), each a one-hidden-layer ReLU network. Direction d is
    judged on the features turned so that its ray is ray 0; waiting in the frame of
    direction 0. ``feat`` is scratch of length 8 n_rays (each block written twice, so
    that a turn is a slice). This is the model's whole evaluation, compiled: a decision
    budget of a few µs leaves no room for numpy's per-call overhead on 17 small
    products."""
    n = s.shape[0]
    per = n // n_dir
    ring_features(s, prev, static, feat)
    for d in range(n_dir):
        out[d] = safety_of(net_t, 0, d * per, feat, n)
    out[n_dir] = safety_of(net_t, 1, 0, feat, n)


@dataclass(frozen=True, eq=False)
class SafetyModel:
    """What the probes taught: the safety model's weights and per-template priors."""

    net: NDArray[np.float64]
    """(2, h + 1, 1 + 4 n_rays): the networks judging a move along ray 0, and waiting,
    each a one-hidden-layer ReLU network: rows 0..h-1 are [bias, weights] of the hidden
    units, row h is [output bias, output weights, 0...] (the kernels take it as
    :func:`kernel_net` lays it out; see :func:`safety_probabilities`)."""
    template_safe: NDArray[np.float64]
    """(n_templates, n_directions): Laplace-smoothed P(safe | template, direction in the
    template's frame)."""
    template_counts: NDArray[np.float64]
    """(n_templates, n_directions): probes behind each entry."""
    static_aware: bool = False
    """Whether the networks were learnt with the static map's reading (their closeness
    block then sees only the hits the static map does not explain: what moves); if not,
    they were learnt, and are evaluated, without one."""


@dataclass(frozen=True)
class Probes:
    """Probe outcomes: per state, the reading, the previous one, and for each compass
    direction and waiting (last column) whether it was safe; and the reading the static
    map alone gives there (what a ``map``-level agent is handed; inf: unknown)."""

    readings: NDArray[np.float64]
    previous: NDArray[np.float64]
    safe: NDArray[np.bool_]
    static: NDArray[np.float64]

    def __getitem__(self, rows: slice) -> Probes:
        """The probes of states ``rows``."""
        return Probes(self.readings[rows], self.previous[rows], self.safe[rows],
                      self.static[rows])  # fmt: skip


def _fork(sim: Simulator) -> Simulator:
    """A copy of ``sim`` whose future obstacle motion is the same as ``sim``'s (the world
    shared, the mutable state and the random generator's state copied)."""
    c = copy.copy(sim)
    c.position = sim.position.copy()
    c.centers = sim.centers.copy()
    c.headings = copy.copy(sim.headings)  # an array (copy.copy of an ndarray copies it)
    c.ranges = sim.ranges.copy()
    c._action = np.zeros(2)
    c.record = False
    bg = type(sim.rng.bit_generator)()
    bg.state = sim.rng.bit_generator.state
    c.rng = np.random.Generator(bg)
    return c


PROBE_LABELS = ("hold", "escape")
"""How a probe is judged safe: its action held ``horizon`` steps without contact, or
taken once leaving a clear second move (see the module's docstring)."""
ESCAPE_CLEAR = 0.2
"""Room (agent steps) an ``escape`` probe's second move keeps from every obstacle's next
step: the model-oracle's margin and escape margin (0.1 + 0.1)."""


WALL_ROOM = 1e-9
"""A second move counts as free of walls when it stops no nearer than this to its end."""


@njit(cache=True)
def second_move_clear(qx, qy, r, segs, c1, c2, radii, moves, clear):  # type: ignore[no-untyped-def]
    """Whether an agent of radius ``r`` at (qx, qy) has a move among ``moves`` (velocities,
    one step) that no wall (``segs``) stops short and that passes every obstacle moving
    linearly from ``c1`` to ``c2`` (radii ``radii``) with ``clear`` to spare: the
    model-oracle's own test (:func:`copi.ceilings._kernels.escapes`) on one future, with
    :data:`WALL_ROOM` to spare from walls where the oracle keeps 1e-6."""
    free = np.empty(moves.shape[0], dtype=np.bool_)
    local = local_segments(qx, qy, segs, 1.0 + r + 1e-3)  # a move is at most 1 long
    free_moves(qx, qy, r, local, moves, free, WALL_ROOM)
    return escapes(qx, qy, r, moves, free, c1, c2, radii, np.arange(c1.shape[0]),
                   c1.shape[0], clear)  # fmt: skip


def _probe_row(sim: Simulator, actions: NDArray[np.float64], horizon: int, label: str,
               seconds: NDArray[np.float64]) -> NDArray[np.bool_]:
    """Each action's probe outcome from ``sim``'s state (see the module's docstring)."""
    row = np.empty(len(actions), dtype=bool)
    if label == "escape":
        # the obstacles' next two positions: they do not depend on the agent's moves
        ahead = _fork(sim)
        ahead.step(np.zeros(2))
        c1 = ahead.centers.copy()
        ahead.step(np.zeros(2))
        c2 = ahead.centers.copy()
        segs = np.ascontiguousarray(sim.world.segments)
    for a, act in enumerate(actions):
        c = _fork(sim)
        if label == "escape":
            row[a] = not c.step(act).contact and second_move_clear(
                c.position[0], c.position[1], c.agent_radius, segs, c1, c2, sim.radii,
                seconds, ESCAPE_CLEAR,
            )  # fmt: skip
            continue
        ok = True
        for _ in range(horizon):
            if c.step(act).contact:
                ok = False
                break
        row[a] = ok
    return row


def probe_states(
    family: str | tuple[str, ...],
    worlds: int,
    steps: int,
    *,
    seed: int,
    n_directions: int,
    horizon: int = 3,
    every: int = 2,
    agent_radius: float = 0.3,
    sensor: RangeSensor | None = None,
    progress: Callable[[int, int], None] | None = None,
    label: str = "hold",
) -> Probes:
    """Random walks in ``worlds`` worlds of ``family`` (or of each family in turn),
    among moving obstacles, probing every ``every``-th state with each compass direction
    and waiting, each held ``horizon`` steps (``label="hold"``) or taken once and judged
    by the second moves it leaves (``label="escape"``; see the module's docstring).
    World k draws from ``default_rng([seed, k, 7])`` (apart from exploration's)."""
    if label not in PROBE_LABELS:
        raise InvalidArgumentError(
            f"probe label must be one of {', '.join(PROBE_LABELS)}; got {label!r}"
        )
    families = (family,) if isinstance(family, str) else tuple(family)
    sensor = sensor or RangeSensor()
    angles = 2 * np.pi * np.arange(n_directions) / n_directions
    unit = np.column_stack([np.cos(angles), np.sin(angles)])
    actions = np.vstack([unit, np.zeros((1, 2))])
    seconds = np.ascontiguousarray(np.vstack([unit, 0.5 * unit, np.zeros((1, 2))]))
    readings, previous, safe, statics = [], [], [], []
    none = np.zeros((0, 2))
    for k in range(worlds):
        rng = np.random.default_rng([seed, k, 7])
        fam = families[k % len(families)]
        world = random_world(rng) if fam == "star" else sample_world(fam, rng)
        sim = Simulator.from_world(world, rng, agent_radius=agent_radius, sensor=sensor)
        walk = RandomWalk(seed=rng)
        prev = sim.ranges.copy()
        blocked = False
        for t in range(steps):
            if t % every == 0:
                row = _probe_row(sim, actions, horizon, label, seconds)
                readings.append(sim.ranges.copy())
                previous.append(prev)
                safe.append(row)
                statics.append(sensor.scan(world, sim.position, none, np.zeros(0)))
            prev = sim.ranges.copy()
            result = sim.step(walk(blocked))
            blocked = result.blocked
            if result.contact:  # start afresh: a walk stuck in a disc teaches little
                sim = Simulator.from_world(world, rng, agent_radius=agent_radius, sensor=sensor)
                prev = sim.ranges.copy()
        if progress is not None:
            progress(k + 1, worlds)
    return Probes(np.array(readings), np.array(previous), np.array(safe), np.array(statics))


def _design(probes: Probes, n_directions: int) -> tuple[Any, ...]:
    """Rows (features turned to each direction, plain and mirrored) and labels of the
    direction model; rows and labels of the wait model (each state in the frame of
    direction 0, plain and mirrored)."""
    n = probes.readings.shape[1]
    per = n // n_directions
    f = feature_block(n)
    m = len(probes.readings)
    x_dir = np.empty((m * n_directions * 2, f))
    y_dir = np.empty(m * n_directions * 2, dtype=bool)
    x_wait = np.empty((m * 2, f))
    y_wait = np.empty(m * 2, dtype=bool)
    row = 0
    for i in range(m):
        s, p, st = probes.readings[i], probes.previous[i], probes.static[i]
        for d in range(n_directions):
            for mirror in (False, True):
                _features_into(s, p, st, d * per, mirror, x_dir[row])
                y_dir[row] = probes.safe[i, d]
                row += 1
        for j, mirror in enumerate((False, True)):
            _features_into(s, p, st, 0, mirror, x_wait[2 * i + j])
            y_wait[2 * i + j] = probes.safe[i, n_directions]
    return x_dir, y_dir, x_wait, y_wait


HIDDEN = 16
"""Hidden units of the safety networks (held-out AUC on the star family: a linear model
over the same features 0.78, 8 units 0.92, 16 units 0.93, gradient-boosted trees 0.95)."""


def _fit(x: NDArray[np.float64], y: NDArray[np.bool_], seed: int) -> NDArray[np.float64]:
    """A one-hidden-layer network (:func:`copi.learning._mlp.fit_mlp`, seeded; the same
    on every processor) packed as in :attr:`SafetyModel.net`; a constant label gives a
    constant network."""
    f = x.shape[1]
    net = np.zeros((HIDDEN + 1, 1 + f))
    if y.all() or not y.any():
        p = (y.sum() + 1.0) / (len(y) + 2.0)
        net[HIDDEN, 0] = math.log(p / (1 - p))
        return net
    w1, b1, w2, b2 = fit_mlp(x, y, HIDDEN, alpha=1e-3, max_iter=60, seed=seed)
    net[:HIDDEN, 0] = b1
    net[:HIDDEN, 1:] = w1.T
    net[HIDDEN, 0] = b2
    net[HIDDEN, 1 : 1 + HIDDEN] = w2
    return net


def predict(net: NDArray[np.float64], x: NDArray[np.float64]) -> NDArray[np.float64]:
    """The network's P(safe) for feature rows ``x`` (numpy; for evaluation)."""
    h = net.shape[0] - 1
    z = np.maximum(x @ net[:h, 1:].T + net[:h, 0], 0.0)
    return 1.0 / (1.0 + np.exp(-(z @ net[h, 1 : 1 + h] + net[h, 0])))


def template_directions(matrices: NDArray[np.float64], n_dir: int) -> NDArray[np.int64]:
    """For symmetries ``matrices`` (m, 2, 2), world frame -> template frame: the compass
    index, in the template's frame, of each world compass direction (m, D)."""
    _, dirs = compass(n_dir)
    turned = np.einsum("mij,dj->mdi", matrices, dirs)
    return np.argmax(turned @ dirs.T, axis=2)


def template_priors(
    template: NDArray[np.int64],
    matrices: NDArray[np.float64],
    safe: NDArray[np.bool_],
    n_templates: int,
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """P(safe | template, direction in the template's frame), Laplace-smoothed, and the
    counts behind it. ``template`` (m,): each probed state's template; ``matrices``
    (m, 2, 2): its symmetry g (world frame -> template frame); ``safe`` (m, D): each
    compass direction's outcome in the world frame."""
    m, n_dir = safe.shape
    idx = template_directions(matrices, n_dir)
    hits = np.zeros((n_templates, n_dir))
    counts = np.zeros((n_templates, n_dir))
    rows = np.repeat(np.asarray(template), n_dir)
    np.add.at(counts, (rows, idx.ravel()), 1.0)
    np.add.at(hits, (rows, idx.ravel()), safe.ravel().astype(float))
    return (hits + 1.0) / (counts + 2.0), counts


def learn_safety(
    probes: Probes,
    n_directions: int,
    template: NDArray[np.int64],
    matrices: NDArray[np.float64],
    n_templates: int,
    *,
    seed: int = 0,
    static_aware: bool = False,
) -> tuple[SafetyModel, dict[str, float]]:
    """Fit the safety model and the per-template priors; returns them and statistics
    (probes, safe share, held-out AUC of each, the last fifth of the states held out).
    With ``static_aware`` the networks see the probes' static readings (a ``map``-level
    agent's); otherwise none."""
    from sklearn.metrics import roc_auc_score

    if not static_aware:
        probes = dataclasses.replace(probes, static=np.full(probes.readings.shape, np.inf))
    n_dir = n_directions
    m = len(probes.readings)
    cut = max(1, int(0.8 * m))
    train, test = probes[:cut], probes[cut:]
    xd, yd, xw, yw = _design(train, n_dir)
    w_dir, w_wait = _fit(xd, yd, seed), _fit(xw, yw, seed)
    stats: dict[str, float] = {
        "probed_states": float(m),
        "safe_share": float(probes.safe[:, :n_dir].mean()),
        "wait_safe_share": float(probes.safe[:, n_dir].mean()),
    }
    if len(test.readings):
        txd, tyd, _, _ = _design(test, n_dir)
        score = predict(w_dir, txd)
        if 0 < tyd.sum() < len(tyd):
            stats["heldout_auc"] = float(roc_auc_score(tyd, score))
    safe_t, counts = template_priors(template, matrices, probes.safe[:, :n_dir], n_templates)
    # the template prior judged on the same held-out probes, for comparison
    if len(test.readings) and "heldout_auc" in stats:
        t_safe, _ = template_priors(
            template[:cut], matrices[:cut], probes.safe[:cut, :n_dir], n_templates
        )
        idx = template_directions(matrices[cut:], n_dir)
        prior = t_safe[np.asarray(template[cut:])[:, None], idx]
        stats["template_heldout_auc"] = float(
            roc_auc_score(probes.safe[cut:, :n_dir].ravel(), prior.ravel())
        )
    model = SafetyModel(np.stack([w_dir, w_wait]), safe_t, counts, static_aware)
    return model, stats
