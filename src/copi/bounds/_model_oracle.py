"""The model-predictive oracle: the best an agent can expect that knows the present and
how the world moves, but not its future."""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from copi.bounds._kernels import sample_futures
from copi.core import Agent, Observation, Sensing, Task, check_sensing
from copi.errors import InvalidArgumentError
from copi.planning.futures import FuturesPlanner

__all__ = ["ModelOracle", "TURN_SD"]

TURN_SD = 0.6
"""The standard deviation of a moving obstacle's heading change per step, radians: the
simulator's (:class:`copi.world.Simulator`), the motion model's one parameter that an
agent at level ``oracle`` cannot read off what it sees (it sees positions and the
velocities of the last step: speeds and headings)."""

_RETRIES = 4  # the simulator's headings tried by a disc a wall stops


class ModelOracle(Agent):
    """A reference planner (not a bound: methods that know less match it in most
    families): model-predictive control against the obstacles' motion model (level
    ``oracle``, plus :data:`TURN_SD`).

    Each step it draws ``samples`` futures of every disc's random walk over ``horizon``
    steps, with the simulator's own rule and parameters (the heading and speed each disc
    was seen moving at, its heading turning by N(0, 0.6) a step, walls turning it as they
    turn the simulator's discs). On a window of 0.5-step cells around the agent it then
    values every cell by *hindsight optimisation* (Chong, Givan & Chang 2000; Yoon et al.
    2008; ``plan="hindsight"``, the default): in each sampled future, solved as if it
    were known, the least number of steps through cells clear of every disc (the sum of
    radii plus ``margin``) to the goal or to the horizon, plus the distance to go around
    the walls from there (a future with no way through costs the horizon, the farthest
    distance to go and ``loss``); the cell's value is the mean over the futures. The move
    it makes (16 directions at full and half speed, or waiting) minimises ``loss`` times
    the share of futures in which it is lost (in contact on the first step, by the
    simulator's closest-approach test, or with no second move clear of that future's
    next step by ``escape`` more) plus one step plus the value of the cell it reaches.
    It replans every step. Nothing in it is learnt; its parameters were tuned on
    validation seed 1 (``docs/analysis/benchmark.md``).

    ``plan="mean"`` values cells against the *mean* occupancy instead (the probability
    that a cell is in contact at each step, averaged over the futures, each cell entered
    costing ``risk`` times minus the log of surviving it, the future ``discount``-ed):
    the first version of this oracle, kept as its ablation. Averaging the discs first
    makes every cell a disc may reach in a few steps look risky; planning once per
    future and averaging the plans' costs assumes instead that the agent will see each
    future as it comes (optimistic: it sees it a step at a time). On 200 validation
    episodes a family (seed 1) hindsight succeeds in 119 crowd episodes against 95 for
    the mean occupancy at its own tuned settings (horizon 10, escape 0.4), 185 against
    177 in polygon and 196 against 185 indoors.

    ``plan="greedy"`` looks no further than the first move's check: a cell's value is
    its distance to go around the walls, nothing planned through the discs' futures
    (futures of two steps are drawn, all the check needs). It measures how much of the
    oracle's edge over the hand-written guards is knowing where the discs will be in the
    next two steps, and how much is planning beyond them: on the 200 validation crowd
    episodes it succeeds in 111 (hindsight 119, compass-guard at map 86).

    What it knows beyond every baseline is exactly the motion model: a method at level
    ``oracle`` sees where the discs are and how they moved last; this one also knows how
    they will move, in distribution. It does not know their future (the clairvoyant
    bound does).

    Parameters
    ----------
    samples : int
        Futures drawn per step (1 .. 256).
    horizon : int
        Steps each future runs (2 .. 40); 10, the most successes of three horizons on
        600 crowd and 300 indoor validation episodes (docs/predictive-horizon.md).
    plan : str
        How cells are valued: ``"hindsight"`` (per future, then averaged), ``"mean"``
        (against the mean occupancy) or ``"greedy"`` (the distance to go alone), see
        above.
    risk : float
        ``plan="mean"``: cost, in steps, of a certain contact's log-odds of surviving.
    loss : float
        Cost, in steps, of a future in which the agent is lost.
    discount : float
        ``plan="mean"``: weight of each later step's risk against the one before.
    margin : float
        Added to the sum of radii when a cell or a first move counts as in contact.
    escape : float
        Added to ``margin`` for the second move that must be left clear.
    seed : int
        Seeds the futures drawn (the same episode, the same moves).
    """

    name = "model-oracle"
    sensing: Sensing = "oracle"
    steers_itself = True  # it plans on the static world itself

    def __init__(
        self,
        *,
        samples: int = 32,
        horizon: int = 10,
        plan: str = "hindsight",
        risk: float = 10.0,
        loss: float = 200.0,
        discount: float = 0.3,
        margin: float = 0.1,
        escape: float = 0.1,
        seed: int = 0,
    ) -> None:
        if int(samples) != samples or not 1 <= samples <= 256:
            raise InvalidArgumentError(
                f"samples must be a whole number in 1 .. 256; got {samples!r}"
            )
        self.planner = FuturesPlanner(horizon=horizon, plan=plan, risk=risk, loss=loss,
                                      discount=discount, margin=margin, escape=escape)  # fmt: skip
        self.samples = int(samples)
        self.horizon = int(horizon)
        self.risk = float(risk)
        self.loss = float(loss)
        self.discount = float(discount)
        self.escape = float(escape)
        self.margin = float(margin)
        self.seed = int(seed)
        self.plan_kind = plan
        self.moves = self.planner.moves
        self._risks: list[float] = []
        # the motion model: the simulator's turn spread; a disc seen waiting moves at the
        # others' greatest speed (a subclass that estimates them sets both each step)
        self.turn_sd = TURN_SD
        self.fallback_speed = 0.0

    def reset(self, task: Task) -> None:
        check_sensing(task.sensing, self.sensing, method=self.name)
        if task.world is None or task.goal is None:
            raise InvalidArgumentError(
                f"{self.name} needs the world and the goal (level {self.sensing!r}); got a "
                f"task at {task.sensing!r} without them"
            )
        self.rng = np.random.default_rng(self.seed)
        self.planner.reset(task.world, np.asarray(task.goal, dtype=np.float64),
                           float(task.agent_radius), float(task.goal_tolerance))  # fmt: skip
        pl = self.planner
        self.r, self.tol, self.goal, self.segs = pl.r, pl.tol, pl.goal, pl.segs
        self.field, self.clear, self.fine = pl.field, pl.clear, pl.fine
        self._risks = []

    def act(self, obs: Observation) -> NDArray[np.float64]:
        if obs.position is None or obs.obstacles is None:
            raise InvalidArgumentError("model-oracle needs the obstacles (level 'oracle')")
        p = obs.position
        obstacles = np.ascontiguousarray(obs.obstacles, dtype=np.float64).reshape(-1, 5)
        radii = np.ascontiguousarray(obstacles[:, 4])
        f = self.field
        seed = int(self.rng.integers(2**31 - 1))
        samples = sample_futures(obstacles, self.segs, self.samples, self.planner.steps,
                                 self.turn_sd, _RETRIES, seed, self.clear, f.x0, f.y0,
                                 self.fine, self.fallback_speed)  # fmt: skip
        return self.plan(p, samples, radii)

    def plan(
        self, p: NDArray[np.float64], samples: NDArray[np.float64], radii: NDArray[np.float64]
    ) -> NDArray[np.float64]:
        """The move from ``p`` against sampled futures of the discs (see
        :meth:`copi.planning.futures.FuturesPlanner.plan`)."""
        m, risk = self.planner.plan(p, samples, radii)
        self._risks.append(risk)
        return np.zeros(2) if m < 0 else self.moves[m].copy()

    def counters(self) -> dict[str, Any]:
        r = self._risks
        return {"mean_risk": float(np.mean(r)) if r else 0.0,
                "max_risk": float(np.max(r)) if r else 0.0}  # fmt: skip
