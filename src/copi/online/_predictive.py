"""``copi-predictive``: copi's learnt parts carry the decision, with no hand-written guard.

Each step the agent follows what moves in its reading (:class:`copi.learning.MotionTracker`),
draws futures of it from its learnt model of what moves (:func:`copi.learning.sample_motion`,
learnt once, without any task, from its own walks: :mod:`copi.learning._motion`), and
plans its move over them (:class:`copi.planning.futures.FuturesPlanner`, the planner the
model-oracle runs on the true motion model), each move also costing what the learnt
safety network says of it (the network over the reading turned to the move, shared by
every direction through the symmetry group: paper §II-C, §II-D) and, with ``beta``, what
the template of the recognised context says of it (§III). Nothing in the decision is a
hand-written rule about obstacles: the simulator's tests of walls and contacts are what
the planner checks its moves with, against futures the agent learnt to expect.

At level ``sensor`` (no map, no position) the agent places itself in the goal's frame
(minus the relative goal) and tells what moves from walls by what it has seen before: a
hit in a cell its rays have passed through more than they stopped in (the occupancy grid
of :class:`~copi.online.Mapping`) is something that moved there; the other hits are
walls, joined into segments where neighbouring rays' hits are close, and so are the
walls it has learnt on that grid (cells hit four times more than passed through). It
plans each step in a box around itself whose only walls are those, unknown space taken
as free.
"""

from __future__ import annotations

import math
import os
from collections.abc import Sequence
from concurrent.futures import ThreadPoolExecutor
from typing import Any

import numpy as np
from numpy.typing import NDArray

from copi._validation import check_flag
from copi.core import Agent, Observation, Sensing, Task, check_sensing
from copi.errors import InvalidArgumentError
from copi.learning import Capabilities, MotionTracker, motion_tables, sample_motion
from copi.learning.kernels import kernel_net, safety_probabilities
from copi.online._learnt import node_priors
from copi.online._mapping import Mapping
from copi.planning.futures import RES, FuturesPlanner

__all__ = ["PredictiveAgent"]

_CLUSTER, _SPAN = 1.0, 3.0
"""Level sensor: neighbouring rays' hits within ``_CLUSTER`` of each other are one
surface, and a surface at most ``_SPAN`` across may be a body (the families' discs are
at most 2 across; a wall seen by rays 2 pi / 32 apart is longer). One setting, kept over
none on validation seed 1 (crowd: 14 of 30 episodes against 10)."""


def _whole_bodies(hit: NDArray[np.bool_], ends: NDArray[np.float64],
                  moved: NDArray[np.bool_]) -> NDArray[np.bool_]:  # fmt: skip
    """``moved``, grown to every hit of a small group (neighbouring rays' hits within
    ``_CLUSTER`` of each other, ``_SPAN`` across at most: a body, not a wall) one of whose
    hits moved: a body's hits are its own whichever of them last fell in seen space."""
    n = len(hit)
    nxt = np.roll(np.arange(n), -1)
    link = hit & hit[nxt] & (np.hypot(*(ends - ends[nxt]).T) <= _CLUSTER)
    if link.all():
        return moved
    out = moved.copy()
    start = int(np.flatnonzero(~link)[0]) + 1  # a group begins after a broken link
    group: list[int] = []
    for step in range(n + 1):
        i = (start + step) % n
        if step < n and hit[i]:
            group.append(i)
        if step == n or not (hit[i] and link[i]):
            if group and moved[group].any():
                if np.hypot(*(ends[group[0]] - ends[group[-1]])) <= _SPAN:
                    out[group] = True
            group = []
    return out


class PredictiveAgent(Agent):
    """copi's ``predictive`` preset as an :class:`~copi.core.Agent`: at level ``map`` it
    tells what moves from what the static map alone would read; at ``sensor``, from what
    its rays have seen free before (see the module).

    The move minimises, over the learnt model's ``samples`` futures of ``horizon``
    steps, the planner's expected cost (:class:`~copi.planning.futures.FuturesPlanner`:
    ``loss`` for a future in which it is lost, one step a move, the steps still to go),
    plus ``alpha`` times minus the log of the safety network's P(safe) of its direction
    (or of waiting), plus ``beta`` times minus the log of the recognised template's
    prior of that direction (read through the context's symmetry).

    Parameters
    ----------
    capabilities : Capabilities
        Learnt with a model of what moves and safety priors (``copi learn --preset
        predictive``).
    samples, horizon, loss, margin, escape, together : see :class:`FuturesPlanner`
        (the model-oracle's settings, but a horizon of 12 steps: the most successes of
        four horizons on 600 crowd and 300 indoor validation episodes with two draws of
        the futures, docs/predictive-horizon.md; each future valued alone, as the
        model-oracle does).
    alpha, beta : float
        Weights, in steps, of the learnt safety network and of the template priors
        (``alpha`` 2: the most successes of five settings on validation seed 1,
        docs/tuning-predictive.md).
    split : bool
        Cut an arc of hits one circle fits badly into several bodies
        (:func:`copi.learning.detect_discs`; docs/predictive-failures.md measures it).
    seed : int
        Seeds the futures drawn (the same episode, the same moves).
    """

    sensing: Sensing = "sensor"
    steers_itself = True  # it plans on the static world (or the walls it sees) itself

    def __init__(
        self,
        capabilities: Capabilities,
        *,
        name: str = "copi-predictive",
        samples: int = 32,
        horizon: int = 12,
        alpha: float = 2.0,
        beta: float = 0.0,
        loss: float = 200.0,
        margin: float = 0.1,
        escape: float = 0.1,
        together: int = 1,
        split: bool = False,
        seed: int = 0,
    ) -> None:
        if capabilities.motion_model is None or capabilities.safety is None:
            raise InvalidArgumentError(
                "these capabilities have no model of what moves (or no safety network), "
                "which copi-predictive plans with: learn them with copi learn --preset "
                "predictive"
            )
        if int(samples) != samples or not 1 <= samples <= 256:
            raise InvalidArgumentError(f"samples must be a whole number in 1 .. 256; got "
                                       f"{samples!r}")  # fmt: skip
        for key, v in (("alpha", alpha), ("beta", beta)):
            if not (isinstance(v, int | float) and math.isfinite(v) and 0 <= v <= 1e3):
                raise InvalidArgumentError(f"{key} must be a number in [0, 1000]; got {v!r}")
        self.planner = FuturesPlanner(horizon=horizon, loss=loss, margin=margin, escape=escape,
                                      together=together)  # fmt: skip
        self.capabilities = capabilities
        self.name = name
        self.samples = int(samples)
        self.alpha = float(alpha)
        self.beta = float(beta)
        self.seed = int(seed)
        self.split = check_flag(split, "split")
        self.model = capabilities.motion_model
        self._tables = motion_tables(self.model)
        self._net = kernel_net(capabilities.safety.net)
        self._static_aware = capabilities.safety.static_aware
        n_dir = capabilities.safety.template_safe.shape[1]
        moves = self.planner.moves
        if len(moves) != 2 * n_dir + 1:
            raise InvalidArgumentError(f"the capabilities have {n_dir} directions; the planner "
                                       f"moves in {(len(moves) - 1) // 2}")  # fmt: skip
        # each planner move's direction among the safety network's (the last: waiting)
        self._dir_of = np.concatenate([np.arange(n_dir), np.arange(n_dir), [n_dir]])
        self._prior = node_priors(capabilities, capabilities.safety) if beta > 0 else None
        self._feat = np.empty(8 * capabilities.n_rays)
        self._p = np.empty(n_dir + 1)
        self.explain = False
        """Keep what each decision rested on in :attr:`last_explained` (copi watch)."""
        self.last_explained: dict[str, Any] | None = None

    def reset(self, task: Task) -> None:
        check_sensing(task.sensing, self.sensing, method=self.name)
        if task.n_rays != self.capabilities.n_rays:
            raise InvalidArgumentError(
                f"the capabilities were learnt for {self.capabilities.n_rays} rays; the "
                f"sensor has {task.n_rays}"
            )
        self.task = task
        self.seen: Mapping | None = None
        if task.world is None or task.goal is None:  # sensor: the walls it sees
            self.seen = Mapping()
            self.seen.reset(task.n_rays, task.max_range, task.agent_radius)
        else:
            self.planner.reset(task.world, np.asarray(task.goal, dtype=np.float64),
                               float(task.agent_radius), float(task.goal_tolerance))  # fmt: skip
        prior = self.model.priors()  # learnt, where a hand-written tracker sets its own
        self.tracker = MotionTracker(task.n_rays, task.max_range, speed=prior["speed"],
                                     turn_sd=prior["turn_sd"], split=self.split)  # fmt: skip
        self.rng = np.random.default_rng(self.seed)
        self._prev: NDArray[np.float64] | None = None
        self._bodies: list[int] = []
        self._risks: list[float] = []
        self.n_waits = 0

    def move_costs(self, obs: Observation) -> NDArray[np.float64]:
        """What the learnt safety network (and with ``beta``, the template prior) adds
        to each of the planner's moves, in steps."""
        s = np.asarray(obs.ranges, dtype=np.float64)
        prev = s if self._prev is None else self._prev
        static = (np.asarray(obs.static, dtype=np.float64)
                  if self._static_aware and obs.static is not None
                  else np.full(len(s), np.inf))  # fmt: skip
        n_dir = len(self._p) - 1
        safety_probabilities(s, prev, static, self._net, n_dir, self._feat, self._p)
        cost = -self.alpha * np.log(np.maximum(self._p, 1e-6))
        if self._prior is not None:
            caps = self.capabilities
            q = caps.contexts(s, prev)
            node = int(np.argmin(((caps.nodes - q) ** 2).sum(axis=1)))
            prior = np.append(self._prior[node], 1.0)  # waiting: no prior
            cost = cost - self.beta * np.log(np.maximum(prior, 1e-6))
        return np.ascontiguousarray(cost[self._dir_of])

    def sees(self, obs: Observation) -> tuple[NDArray[np.float64], NDArray[np.float64],
                                              NDArray[np.float64]]:  # fmt: skip
        """Level ``sensor``: (its position in the goal's frame, the reading of the hits
        it takes for walls (the maximum range elsewhere), the walls as segments), and
        the reading folded into what it has seen."""
        seen = self.seen
        assert seen is not None
        p = -np.asarray(obs.goal, dtype=np.float64)
        r = np.asarray(obs.ranges, dtype=np.float64)
        hit = r < seen.max_range
        ends = p + r[:, None] * seen._dirs
        ij = seen._index(ends)
        moved = hit & (seen.occupancy[ij[:, 1], ij[:, 0]] < 0.0)  # where rays passed
        moved = _whole_bodies(hit, ends, moved)
        seen.update(r, p)
        wall = hit & ~moved
        static = np.where(wall, r, seen.max_range)
        nxt = np.roll(np.arange(len(r)), -1)
        join = wall & wall[nxt] & (np.hypot(*(ends - ends[nxt]).T) <= seen.join)
        segs = np.vstack([np.hstack([ends[join], ends[nxt][join]]),
                          np.hstack([ends[wall], ends[wall]])])  # fmt: skip
        return p, static, np.vstack([segs, self._remembered(p)])

    def _remembered(self, p: NDArray[np.float64]) -> NDArray[np.float64]:
        """The walls it has learnt on its grid in the planner's box around ``p``, as
        points at the cells' centres: the cells whose occupancy is ``Mapping.wall_level``
        or more (hit four times more than rays passed through them; not also hit
        ``Mapping.wall_hits`` times in all, as the mapping strategy asks before it
        hands a wall on as static: on validation seed 1, 151 successes of 240 against
        141)."""
        seen = self.seen
        assert seen is not None
        reach = (self.planner.half + 3) * RES  # reset_open's box
        lo = seen._index((p - reach)[None])[0]
        hi = seen._index((p + reach)[None])[0]
        occ = seen.occupancy[lo[1] : hi[1] + 1, lo[0] : hi[0] + 1]
        iy, ix = np.nonzero(occ >= seen.wall_level)
        c = seen._centre(np.column_stack([ix + lo[0], iy + lo[1]]))
        return np.hstack([c, c]).reshape(-1, 4)

    def act(self, obs: Observation) -> NDArray[np.float64]:
        if self.seen is not None:
            position, static, segs = self.sees(obs)
            self.planner.reset_open(segs, position, np.zeros(2), self.task.agent_radius,
                                    self.task.goal_tolerance)  # fmt: skip
            obs = Observation(ranges=obs.ranges, goal=obs.goal, position=position,
                              static=static)  # fmt: skip
        elif obs.position is None or obs.static is None:
            raise InvalidArgumentError(f"{self.name} needs its position and the static "
                                       "reading (level 'map')")  # fmt: skip
        assert obs.position is not None and obs.static is not None
        self.tracker.update(obs.ranges, obs.static, obs.position)
        bodies = np.ascontiguousarray(self.tracker.bodies())
        pl = self.planner
        f = pl.field
        seed = int(self.rng.integers(2**31 - 1))
        futures = sample_motion(bodies, pl.segs, self.samples, pl.steps, seed,  # type: ignore[call-arg]
                                *self._tables, pl.clear, f.x0, f.y0, pl.fine)  # fmt: skip
        radii = np.ascontiguousarray(bodies[:, 5])
        extra = self.move_costs(obs)
        m, risk = pl.plan(np.asarray(obs.position, dtype=np.float64), futures, radii, extra)
        self._prev = np.asarray(obs.ranges, dtype=np.float64).copy()
        self._bodies.append(len(bodies))
        self._risks.append(risk)
        self.n_waits += m == len(pl.moves) - 1
        move = np.zeros(2) if m < 0 else pl.moves[m].copy()
        if self.explain:  # for copi watch: the futures it expected and what it chose
            self.last_explained = {"bodies": bodies.copy(), "futures": futures[:8].copy(),
                                   "move": move, "costs": pl.costs.copy(), "lost": pl.lost.copy(),
                                   "extra": extra.copy(), "risk": risk,
                                   "waits": m == len(pl.moves) - 1}  # fmt: skip
        return move

    @staticmethod
    def act_many(
        agents: Sequence[PredictiveAgent],
        observations: Sequence[Observation],
        *,
        workers: int | None = None,
    ) -> NDArray[np.float64]:
        """Many agents' decisions at once (each agent's :meth:`act` on its observation),
        ``workers`` threads at a time (default: the machine's cores): the drawing of
        futures and the planning are compiled kernels that release the GIL, so the
        agents plan in parallel; each agent keeps its own generator, so the moves are the
        same whatever the number of workers. Returns (b, 2)."""
        if len(agents) != len(observations):
            raise InvalidArgumentError(f"one observation per agent: {len(agents)} agents, "
                                       f"{len(observations)} observations")  # fmt: skip
        if workers is not None and (isinstance(workers, bool) or not isinstance(workers, int)
                                    or workers < 1):  # fmt: skip
            raise InvalidArgumentError(f"workers must be a positive int; got {workers!r}")
        n = min(len(agents), workers or os.cpu_count() or 1)
        if n <= 1:
            return np.array([a.act(o) for a, o in zip(agents, observations, strict=True)])
        with ThreadPoolExecutor(n) as pool:
            moves = list(pool.map(lambda a, o: a.act(o), agents, observations))
        return np.array(moves).reshape(-1, 2)

    def counters(self) -> dict[str, Any]:
        """Per-episode diagnostics stored with the result."""
        b, r = self._bodies, self._risks
        return {"mean_bodies": float(np.mean(b)) if b else 0.0,
                "mean_risk": float(np.mean(r)) if r else 0.0,
                "waits": int(self.n_waits)}  # fmt: skip
