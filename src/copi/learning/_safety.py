"""Learnt action priors for safety (paper §II-D, last paragraph, after its ref. [25]):
counterfactual probes from states visited in task-independent exploration.

From a state of a random walk among moving obstacles, the simulator is copied once per
action (each compass direction, and waiting) and the action is held for ``horizon`` steps
while the obstacles keep moving (all copies see the same obstacle motion). A probe is
*safe* when no moving obstacle touches the agent meanwhile (``label="hold"``, the
default). With ``label="escape"`` the action is taken once and the probe is safe when it
touches nothing and leaves a second move (a compass direction at full or half speed, or
waiting) that passes every obstacle's next step with :data:`ESCAPE_CLEAR` to spare:
the model-predictive oracle's own check of a first move (:mod:`copi.bounds`), on the
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

from copi.errors import InvalidArgumentError
from copi.geometry.kernels import escapes, free_moves, local_segments
from copi.learning._mlp import fit_mlp
from copi.learning.kernels import feature_block, features_into, template_directions
from copi.world import RandomWalk, RangeSensor, Simulator, random_world, sample_world

__all__ = [
    "PROBE_LABELS",
    "Probes",
    "SafetyModel",
    "design_matrix",
    "fork_simulator",
    "learn_safety",
    "predict",
    "probe_actions",
    "probe_states",
]


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


def fork_simulator(sim: Simulator) -> Simulator:
    """A copy of ``sim`` whose future obstacle motion is the same as ``sim``'s (the world
    shared, the mutable state and the random generator's state copied)."""
    c = copy.copy(sim)
    c.position = sim.position.copy()
    c.centers = sim.centers.copy()
    c.headings = copy.copy(sim.headings)  # an array (copy.copy of an ndarray copies it)
    c.ranges = sim.ranges.copy()
    c._action = np.zeros(2)
    c.record = False
    if sim.crowd is not None:  # a crowd that reacts: its own copy, stepped alike
        c.crowd = copy.deepcopy(sim.crowd)
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
    model-oracle's own test (:func:`copi.geometry.kernels.escapes`) on one future, with
    :data:`WALL_ROOM` to spare from walls where the oracle keeps 1e-6."""
    free = np.empty(moves.shape[0], dtype=np.bool_)
    local = local_segments(qx, qy, segs, 1.0 + r + 1e-3)  # a move is at most 1 long
    free_moves(qx, qy, r, local, moves, free, WALL_ROOM)
    return escapes(qx, qy, r, moves, free, c1, c2, radii, np.arange(c1.shape[0]),
                   c1.shape[0], clear)  # fmt: skip


def probe_actions(sim: Simulator, actions: NDArray[np.float64], horizon: int, label: str,
               seconds: NDArray[np.float64]) -> NDArray[np.bool_]:
    """Each action's probe outcome from ``sim``'s state (see the module's docstring)."""
    row = np.empty(len(actions), dtype=bool)
    if label == "escape":
        # the obstacles' next two positions: they do not depend on the agent's moves
        ahead = fork_simulator(sim)
        ahead.step(np.zeros(2))
        c1 = ahead.centers.copy()
        ahead.step(np.zeros(2))
        c2 = ahead.centers.copy()
        segs = np.ascontiguousarray(sim.world.segments)
    for a, act in enumerate(actions):
        c = fork_simulator(sim)
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
                row = probe_actions(sim, actions, horizon, label, seconds)
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


def design_matrix(probes: Probes, n_directions: int) -> tuple[Any, ...]:
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
                features_into(s, p, st, d * per, mirror, x_dir[row])
                y_dir[row] = probes.safe[i, d]
                row += 1
        for j, mirror in enumerate((False, True)):
            features_into(s, p, st, 0, mirror, x_wait[2 * i + j])
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
    xd, yd, xw, yw = design_matrix(train, n_dir)
    w_dir, w_wait = _fit(xd, yd, seed), _fit(xw, yw, seed)
    stats: dict[str, float] = {
        "probed_states": float(m),
        "safe_share": float(probes.safe[:, :n_dir].mean()),
        "wait_safe_share": float(probes.safe[:, n_dir].mean()),
    }
    if len(test.readings):
        txd, tyd, _, _ = design_matrix(test, n_dir)
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
