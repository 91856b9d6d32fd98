"""The ``learnt`` preset's agent: capabilities whose learnt safety carries the choice."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import NDArray

from copi.core import Agent, Observation, Task
from copi.errors import InvalidArgumentError
from copi.learning import Capabilities, SafetyModel
from copi.learning.kernels import kernel_net, template_directions
from copi.online import _learnt_kernels
from copi.online._agent import Steering
from copi.online._controller import ContextController, screen_nodes, screen_products

__all__ = ["LearntAgent", "node_priors"]


def node_priors(caps: Capabilities, model: SafetyModel) -> NDArray[np.float64]:
    """Per context-map node, P(safe) of each compass direction in the world frame: its
    template's prior (learnt in the template's frame) read through the node's symmetry
    g (direction d in the world is g d in the template's frame). Shape (n_nodes, D)."""
    mats = caps.group.matrices[caps.node_element]  # (n, 2, 2): world -> template
    idx = template_directions(mats, model.template_safe.shape[1])
    return np.ascontiguousarray(model.template_safe[caps.node_template[:, None], idx])


class LearntAgent(Agent):
    """copi's ``learnt`` preset as an :class:`~copi.online.Agent` (paper §II-D, §III).

    Each step the reading is recognised (nearest context-map node, its template and
    symmetry), every compass direction and waiting is scored by the global direction
    and by what the probes taught — the safety network over the reading turned to that
    direction, and the template's prior through the symmetry — and the best one that a
    hand-written guard allows is taken (see :func:`copi.online._learnt_kernels.decide_learnt`).
    With ``alpha = beta = 0`` and no waiting this is ``compass-guard`` at the same guard:
    the ablation of everything learnt (the benchmark's compass-guard has its guard tuned
    on its own, docs/tuning.md).

    Parameters
    ----------
    capabilities : Capabilities
        Learnt with safety probes (``copi learn --preset learnt``).
    guard : float
        The hand-written guard's reach (0: none).
    alpha, beta : float
        Weights of the safety network and of the template priors.
    wait : bool
        Standing still is among the behaviours.
    continual : bool
        Grow the context map for unfamiliar readings as the agent goes (paper §II-A,
        §III: GNG learning reinstated), each new node given the landmark and symmetry
        that fit it best (as :class:`~copi.online.ContextController` does); in a lifelong
        run the grown contexts are kept from task to task.
    grow_every : int
        Unfamiliar readings per node grown (the second map's GNG lambda).
    persist : float
        Policies that last (an option in the paper's sense, §V): while the reading
        stays within the landmark of the previous decision, the previous direction
        scores this much more (0: every step chooses afresh).
    """

    sensing = "sensor"
    steers_itself = True

    def __init__(
        self,
        capabilities: Capabilities,
        *,
        name: str = "copi-learnt",
        guard: float = 1.05,
        alpha: float = 1.0,
        beta: float = 0.0,
        wait: bool = False,
        continual: bool = False,
        grow_every: int = 20,
        persist: float = 0.0,
        safety: SafetyModel | None = None,
    ) -> None:
        model = safety if safety is not None else capabilities.safety
        if model is None:
            raise InvalidArgumentError(
                "these capabilities have no safety priors (the learnt preset needs them): "
                "learn them with copi learn --preset learnt"
            )
        self.capabilities = capabilities
        self.name = name
        self.explain = False
        """Keep what each decision rested on in :attr:`last_explained` (copi watch)."""
        self.last_explained: dict[str, Any] | None = None
        self.guard = float(guard)
        for key, v in (("alpha", alpha), ("beta", beta)):
            # a direction's alignment bounds its score only for weights >= 0
            if not (isinstance(v, int | float) and math.isfinite(v) and v >= 0):
                raise InvalidArgumentError(f"{key} must be a finite number >= 0; got {v!r}")
        self.alpha = float(alpha)
        self.beta = float(beta)
        self.wait = bool(wait)
        self.model = model
        self._net = kernel_net(model.net)  # the kernels' layout
        self._nodes = np.ascontiguousarray(capabilities.nodes, dtype=np.float64)
        self._nodes_t = np.ascontiguousarray(self._nodes.T)  # the kernels' layout (dim, n)
        self._screen: NDArray[np.float32] | None = None  # decide_batch's screen, when used
        self._gram: NDArray[np.float32] | None = None
        self._prior = node_priors(capabilities, model)
        self._compass = _learnt_kernels.compass_table(self._prior.shape[1])
        n = capabilities.n_rays
        a = 2 * np.pi * np.arange(n) / n
        self._cos, self._sin = np.cos(a), np.sin(a)
        self._feat = np.empty(8 * n)
        self._p = np.empty(self._prior.shape[1] + 1)
        self._out = np.empty(5)
        self.max_range = float(capabilities.params.get("max_range", 10.0))
        self.steering = Steering()
        self._prev: NDArray[np.float64] | None = None
        self.n_waits = 0
        self.n_decisions = 0
        self.n_unfamiliar = 0
        self.continual = bool(continual)
        self.grow_every = int(grow_every)
        if not (math.isfinite(persist) and persist >= 0):
            raise InvalidArgumentError(f"persist must be a finite number >= 0; got {persist!r}")
        self.persist = float(persist)
        self._landmarks = np.ascontiguousarray(capabilities.landmarks.node_landmark,
                                               dtype=np.int64)  # fmt: skip
        self._prev_landmark = -1
        self._keep = -1
        self.threshold = float(capabilities.stats.get("familiarity_threshold", np.inf))
        self._templates = np.asarray(capabilities.node_template, dtype=np.int64)
        self._growth: ContextController | None = None
        self._context = -1

    def reset(self, task: Task) -> None:
        if task.n_rays != self.capabilities.n_rays:
            raise InvalidArgumentError(
                f"the capabilities were learnt for {self.capabilities.n_rays} rays; "
                f"the sensor has {task.n_rays}"
            )
        self.max_range = float(task.max_range)
        self._no_static = np.full(task.n_rays, np.inf)
        self.steering.reset(task)
        self._prev = None
        self.n_waits = 0
        self.n_decisions = 0
        self.n_unfamiliar = 0
        self._context = -1
        self._prev_landmark = -1
        self._keep = -1
        if not task.lifelong and self._growth is not None:  # grown contexts: one life only
            self._growth = None
            self._nodes = np.ascontiguousarray(self.capabilities.nodes, dtype=np.float64)
            self._nodes_t = np.ascontiguousarray(self._nodes.T)
            self._screen = None
            self._prior = node_priors(self.capabilities, self.model)
            self._templates = np.asarray(self.capabilities.node_template, dtype=np.int64)

    def act(self, obs: Observation) -> NDArray[np.float64]:
        desired, reach = self.steering.aim(obs, self._context)
        obs = self.steering.observe(obs)
        s = np.asarray(obs.ranges, dtype=np.float64)
        prev = s if self._prev is None else self._prev
        static = self._no_static if obs.static is None else obs.static
        out = self._out
        _learnt_kernels.decide_learnt(
            s, prev, static, self._nodes_t, self._prior, self._net, desired[0], desired[1],
            reach, self.guard, self.alpha, self.beta, self.wait, self._cos, self._sin,
            self.max_range, self._compass, self._feat, self._p, out, self._landmarks,
            self._prev_landmark, self._keep, self.persist, True, self.model.static_aware,
        )  # fmt: skip
        if out[2] < 0:
            what = "not finite and >= 0" if out[2] == -1 else "static reading not >= 0"
            raise InvalidArgumentError(f"ranges must be finite and >= 0; got a reading {what}")
        self._prev = s.copy()
        self.n_decisions += 1
        self.n_waits += out[4] == -4.0
        node = int(out[2])
        if self.explain:  # for copi watch: what the choice rested on
            self.last_explained = {
                "direction": np.array(desired, dtype=np.float64), "node": node,
                "template": int(self._templates[node]), "choice": int(out[4]),
                "safety": self._p[: self._prior.shape[1] + 1].copy(),
            }  # fmt: skip
        self._context = int(self._templates[node])
        self._prev_landmark = int(self._landmarks[node]) if node < len(self._landmarks) else -1
        self._keep = int(out[4]) if out[4] >= 0 else -1
        if out[3] > self.threshold * self.threshold:
            self.n_unfamiliar += 1
            if self.continual:
                self._grow(self.capabilities.contexts(s, prev))
        return out[:2].copy()

    def decide_batch(
        self,
        ranges: Any,
        previous: Any,
        desired: Any,
        reach: Any = None,
        static: Any = None,
        *,
        recognise: bool = True,
    ) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
        """Velocities for many agents at once: row i is the decision :meth:`act` makes
        for reading ``ranges[i]`` after ``previous[i]``, with the global direction
        ``desired[i]`` (no global strategy here: it is given), within ``reach[i]`` (inf
        by default), with ``static[i]`` as the static reading (none by default), and
        without persistence (a batch has no previous decision); not to be called from
        several threads on one agent at once (the screen's buffer is reused). The
        nearest-node search is screened by one float32 matrix product (see
        :func:`copi.online._controller.screen_products`). With ``recognise=False`` (only
        when ``beta`` is 0: the choice then uses no context) the contexts are not
        recognised at all, the same actions come back, and every node is -1; about 40 %
        faster (the speed page). Returns (actions (b, 2), nodes (b,))."""
        n = self.capabilities.n_rays
        s = np.ascontiguousarray(np.asarray(ranges, dtype=np.float64))
        if s.ndim != 2 or s.shape[1] != n:
            raise InvalidArgumentError(f"readings must have shape (b, {n}); got {s.shape}")
        b = len(s)
        prev = np.ascontiguousarray(np.asarray(previous, dtype=np.float64))
        if prev.shape != s.shape:
            raise InvalidArgumentError(
                f"previous readings must have shape {s.shape}; got {prev.shape}"
            )
        want = np.ascontiguousarray(np.asarray(desired, dtype=np.float64))
        if want.shape != (b, 2) or not np.isfinite(want).all():
            raise InvalidArgumentError(
                f"desired must be finite, of shape ({b}, 2); got shape {want.shape}"
            )
        r = np.full(b, np.inf) if reach is None else np.asarray(reach, dtype=np.float64)
        if r.ndim == 0:
            r = np.full(b, float(r))
        if r.shape != (b,) or not (r >= 0).all():
            raise InvalidArgumentError(f"reach must be >= 0, of shape ({b},)")
        st = (
            np.full(s.shape, np.inf)
            if static is None
            else np.ascontiguousarray(np.asarray(static, dtype=np.float64))
        )
        if st.shape != s.shape:
            raise InvalidArgumentError(
                f"static readings must have shape {s.shape}; got {st.shape}"
            )
        if not recognise and self.beta > 0.0:
            raise InvalidArgumentError(
                f"recognise=False needs beta = 0 (the choice then uses no context); "
                f"beta is {self.beta:g}"
            )
        if recognise:
            if self._screen is None:  # first use, or the nodes have grown or moved
                self._screen = screen_nodes(self._nodes)
            q = np.ascontiguousarray(self.capabilities.contexts(s, prev))
            self._gram, sq = screen_products(q, self._screen, self._gram)
            gram = self._gram
        else:
            gram, sq = np.empty((b, 0), dtype=np.float32), np.zeros(b)
        out = np.empty((b, 5))
        _learnt_kernels.decide_learnt_batch(
            s, prev, st, self._nodes_t, gram, sq, self._prior, self._net,
            want, np.ascontiguousarray(r), self.guard, self.alpha, self.beta, self.wait,
            self._cos, self._sin, self.max_range, self._compass, self._feat, self._p, out,
            self.model.static_aware, recognise,
        )  # fmt: skip
        if (out[:, 2] == -1).any():
            raise InvalidArgumentError("readings must be finite and >= 0 (and previous finite)")
        if (out[:, 2] == -2).any():
            raise InvalidArgumentError("static readings must be >= 0")
        nodes = out[:, 2].astype(np.int64) if recognise else np.full(b, -1, dtype=np.int64)
        return out[:, :2].copy(), nodes

    def decide_rows(
        self,
        ranges: NDArray[np.float64],
        positions: NDArray[np.float64],
        goals: NDArray[np.float64],
        active: NDArray[np.bool_],
        lo: int,
        hi: int,
        previous: NDArray[np.float64],
        previous_goal: NDArray[np.float64],
        first: int,
        actions: NDArray[np.float64],
    ) -> None:
        """:meth:`decide_batch` (``recognise=False``: ``beta`` must be 0) for the agents
        ``lo .. hi - 1`` still ``active`` of arrays many agents share (a crowd's, rows of
        shape (N, ...)), in place and in one compiled call: agent i's desired direction
        is the straight line from ``positions[i]`` to ``goals[i]`` (within its length),
        its previous reading ``previous[i - first]``, taken for the goal
        ``previous_goal[i - first]`` (another goal is a new task, with no previous
        reading); its velocity goes to ``actions[i]``, its reading and goal to
        ``previous`` and ``previous_goal``. The same decisions as :meth:`decide_batch`
        (tested)."""
        if self.beta > 0.0:
            raise InvalidArgumentError(
                f"decide_rows decides without recognising the context: beta must be 0; "
                f"got {self.beta:g}"
            )
        n = self.capabilities.n_rays
        if ranges.ndim != 2 or ranges.shape[1] != n:
            raise InvalidArgumentError(f"readings must have shape (N, {n}); got {ranges.shape}")
        big = len(ranges)
        m = len(previous)
        lo, hi, first = int(lo), int(hi), int(first)
        shapes = {
            "positions": (positions, (big, 2)), "goals": (goals, (big, 2)),
            "active": (active, (big,)), "actions": (actions, (big, 2)),
            "previous": (previous, (m, n)), "previous_goal": (previous_goal, (m, 2)),
        }  # fmt: skip
        for key, (a, want) in shapes.items():
            if a.shape != want:
                raise InvalidArgumentError(f"{key} must have shape {want}; got {a.shape}")
        if not (0 <= first <= lo <= hi <= big and hi - first <= m):
            raise InvalidArgumentError(
                f"rows lo .. hi - 1 must lie within the N = {big} agents and the "
                f"{m} previous readings from agent {first}; got lo {lo}, hi {hi}"
            )
        bad = _learnt_kernels.decide_learnt_rows(
            ranges, positions, goals, active, int(lo), int(hi), previous, previous_goal,
            int(first), self._prior, self._net, self.guard, self.alpha, self.beta, self.wait,
            self._cos, self._sin, self.max_range, self._compass, self._feat, self._p, actions,
            self.model.static_aware,
        )  # fmt: skip
        if bad >= 0:
            raise InvalidArgumentError(f"readings must be finite and >= 0; agent {bad}'s "
                                       "is not")  # fmt: skip

    def _grow(self, s: NDArray[np.float64]) -> None:
        """Learn an unfamiliar context into the grown part of the context map."""
        if self._growth is None:
            self._growth = ContextController(self.capabilities, continual=True,
                                             grow_every=self.grow_every,
                                             chain=False)  # fmt: skip
        nodes, _, _ = self._growth._learn_unfamiliar(s)
        base = len(self.capabilities.nodes)
        if len(nodes) == base:  # the second map starts once two readings have come
            return
        # Every update moves the grown nodes (and may change their landmark): refresh.
        g = self._growth
        self._nodes = np.ascontiguousarray(nodes)
        self._nodes_t = np.ascontiguousarray(self._nodes.T)
        self._screen = None
        self._templates = np.concatenate(
            [np.asarray(self.capabilities.node_template, dtype=np.int64), g._extra_template]
        )
        mats = self.capabilities.group.matrices[g._extra_element]
        idx = template_directions(mats, self.model.template_safe.shape[1])
        grown = self.model.template_safe[g._extra_template[:, None], idx]
        self._prior = np.ascontiguousarray(np.concatenate([self._prior[:base], grown]))

    @property
    def n_learnt(self) -> int:
        """Context nodes grown so far (continual)."""
        return 0 if self._growth is None else self._growth.n_learnt

    def finish(self, outcome: str) -> None:
        """The task ended (``outcome``): tells the global strategy."""
        self.steering.finish(outcome)

    def counters(self) -> dict[str, Any]:
        """Per-episode diagnostics stored with the result."""
        rate = self.n_unfamiliar / self.n_decisions if self.n_decisions else 0.0
        return {"unfamiliar": float(rate), "waits": int(self.n_waits), "grown": int(self.n_learnt)}
