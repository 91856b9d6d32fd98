"""SARL, CrowdNav's crowd-navigation peer, at level ``oracle`` (numpy inference).

SARL (Chen, Liu, Kreiss & Alahi, "Crowd-Robot Interaction", ICRA 2019; the CrowdNav
repository's ``crowd_nav/policy/sarl.py`` and ``multi_human_rl.py``) values a joint state
(the robot and every human, positions and velocities known) with a network that attends
over the humans, and acts by a one-step lookahead: each candidate velocity is scored by
the reward of the step it makes plus the discounted value of the state it leads to,
every human carried on at its present velocity. CrowdNav trains it by imitation of ORCA
(the value of each state its demonstrations reach), then by reinforcement learning
(value targets from the next state, epsilon-greedy episodes).

Here, as there, with what copi's worlds add and the level gives (``oracle``: the discs'
positions and velocities, the static reading):

- the frame: x along the level's global direction (the route at ``map`` and above, as
  every copi method follows it), turned by a whole number of rays
  (:func:`~copi.baselines._ppo.direction_frame`) so that the static ring turns exactly;
- the robot's own state (:data:`SELF`): how far the point aimed at lies (over the range,
  clipped to 1), the direction in the frame, its last velocity, its radius;
- each disc's state (:data:`HUMAN`, the nearest :data:`MAX_HUMANS` within the sensor's
  range): its centre relative to the robot, velocity, radius, distance and the sum of
  radii, in the frame (CrowdNav's rotated joint state);
- the walls, which CrowdNav's scenarios do not have: the static reading (32 rays, in the
  frame, over the range) beside the robot's state in the last network (SARL's ``mlp3``);
  a move the static reading shows would reach a wall is not considered;
- the reward (:class:`SARLReward`), in agent steps: progress along the direction, a
  time cost, a proximity penalty for passing closer than ``near`` to a disc, a penalty at
  a contact and a bonus at the goal;
- the actions: CrowdNav's holonomic set, 5 speeds exponentially spaced up to the agent's
  top speed in 16 directions, and standing still (81).

The network's layers are SARL's with smaller widths (:data:`WIDTHS`), so that a decision
(81 actions x up to 8 discs) costs about a millisecond in numpy. Nothing in it is
hand-written but the reward, the lookahead and the feature frame; the weights ship as
``.npz`` with the command that trained them (``copi.rl.sarl``).
"""

from __future__ import annotations

import functools
import json
import math
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from copi._files import write_npz
from copi._npz import read_metadata, read_npz
from copi.baselines._common import Steered
from copi.baselines._ppo import POLICIES, direction_frame
from copi.core import Observation, Sensing, Task
from copi.errors import CopiError, InvalidArgumentError

__all__ = [
    "HUMAN",
    "MAX_HUMANS",
    "SELF",
    "SARLAgent",
    "SARLFormatError",
    "SARLReward",
    "SARLWeights",
    "load_sarl",
    "lookahead_states",
    "sarl_actions",
    "sarl_state",
    "sarl_values",
    "save_sarl",
]

FORMAT = "copi-sarl"
FORMAT_VERSION = 1
SELF = 6
"""The robot's state: reach over the range, the direction in the frame (2), its last
velocity in the frame (2), its radius."""
HUMAN = 7
"""A disc's state: its centre relative to the robot over the range (2), velocity (2),
radius, distance over the range, sum of radii."""
MAX_HUMANS = 8
"""The discs a state holds: the nearest within the sensor's range."""
WIDTHS = {"mlp1": (64, 64), "mlp2": (64, 32), "attention": (64, 64, 1), "mlp3": (128, 64, 1)}
"""Widths of SARL's four networks (CrowdNav's: 150-100, 100-50, 100-100-1, 150-100-100-1)."""
NETS = ("mlp1", "mlp2", "attention", "mlp3")
MAX_WIDTH = 1024


class SARLFormatError(CopiError):
    """A file that is not a SARL value network copi can run."""


@dataclass(frozen=True)
class SARLReward:
    """The reward of one step, in agent steps (see the module)."""

    progress: float = 0.05
    time: float = 0.01
    success: float = 1.0
    contact: float = 1.0
    proximity: float = 0.5
    near: float = 1.0
    """Gap below which a step costs up to ``proximity`` (CrowdNav's discomfort distance,
    0.2 m, is 0.8 agent steps)."""
    gamma: float = 0.95
    """Discount a step (CrowdNav's 0.9 a second is 0.974 a step of 0.25 m)."""

    def __post_init__(self) -> None:
        for k, v in vars(self).items():
            if not (isinstance(v, int | float) and not isinstance(v, bool)
                    and 0 <= v <= 1000 and math.isfinite(v)):  # fmt: skip
                raise InvalidArgumentError(f"SARL reward {k} must be a number in [0, 1000]; "
                                           f"got {v!r}"[:200])  # fmt: skip
        if not 0 < self.gamma < 1 or self.near <= 0:
            raise InvalidArgumentError("SARL reward gamma must lie in (0, 1) and near above 0; "
                                       f"got {self.gamma!r}, {self.near!r}")  # fmt: skip


def sarl_actions(speeds: int = 5, headings: int = 16) -> NDArray[np.float64]:
    """CrowdNav's holonomic action set in the frame, shape (speeds * headings + 1, 2):
    speeds (e^(i/speeds) - 1) / (e - 1) for i = 1 .. speeds (the last the top speed, 1)
    in ``headings`` directions from the frame's x axis, then standing still."""
    v = np.array([(math.exp((i + 1) / speeds) - 1) / (math.e - 1) for i in range(speeds)])
    a = 2 * np.pi * np.arange(headings) / headings
    moves = (v[:, None, None] * np.stack([np.cos(a), np.sin(a)], axis=1)[None]).reshape(-1, 2)
    return np.vstack([moves, np.zeros((1, 2))])


def _turn(xy: NDArray[np.float64], k: int, n: int) -> NDArray[np.float64]:
    """World-frame vectors (..., 2) in the frame of ``k`` rays of ``n``."""
    a = 2 * math.pi * k / n
    c, s = math.cos(a), math.sin(a)
    out = np.empty_like(xy)
    out[..., 0] = c * xy[..., 0] + s * xy[..., 1]
    out[..., 1] = -s * xy[..., 0] + c * xy[..., 1]
    return out


def sarl_state(
    obs: Observation,
    direction: Any,
    reach: float,
    velocity: Any,
    radius: float,
    max_range: float,
) -> tuple[int, NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """The present joint state of an ``oracle`` observation: (k, self (SELF,), discs (h,
    HUMAN) nearest first, static (n_rays,) over the range), all in the frame of ``k`` rays
    (:func:`~copi.baselines._ppo.direction_frame` of ``direction``, of any length: its
    unit vector is kept); ``velocity`` is the robot's last move (world frame)."""
    if obs.obstacles is None or obs.static is None:
        raise InvalidArgumentError("SARL needs an oracle's observation (the discs and the "
                                   "static reading)")  # fmt: skip
    n = obs.ranges.shape[0]
    k = direction_frame(direction, n)
    u = _turn(np.asarray(direction, dtype=np.float64), k, n)
    norm = math.hypot(u[0], u[1])
    if norm > 0.0:
        u /= norm
    me = np.empty(SELF)
    me[0] = min(1.0, max(0.0, reach) / max_range)
    me[1:3] = u
    me[3:5] = _turn(np.asarray(velocity, dtype=np.float64), k, n)
    me[5] = radius
    static = np.minimum(np.roll(obs.static, -k), max_range) / max_range
    o = np.asarray(obs.obstacles, dtype=np.float64).reshape(-1, 5)
    pos = obs.position if obs.position is not None else np.zeros(2)
    rel = o[:, :2] - pos
    d = np.hypot(rel[:, 0], rel[:, 1])
    near = np.flatnonzero(d - o[:, 4] < max_range)
    near = near[np.argsort(d[near], kind="stable")][:MAX_HUMANS]
    h = np.empty((len(near), HUMAN))
    h[:, :2] = _turn(rel[near], k, n) / max_range
    h[:, 2:4] = _turn(o[near, 2:4], k, n)
    h[:, 4] = o[near, 4]
    h[:, 5] = d[near] / max_range
    h[:, 6] = o[near, 4] + radius
    return k, me, h, static


def lookahead_states(
    me: NDArray[np.float64],
    humans: NDArray[np.float64],
    actions: NDArray[np.float64],
    max_range: float,
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """For each action (A, 2) of the frame, the state after it (every disc carried on at
    its velocity: SARL's propagation): self (A, SELF), discs (A, h, HUMAN), the least
    gap between the robot's surface and a disc's over the step (A,) (the closest approach
    of the two straight moves: a contact below 0) and at its end (A,) (inf with no
    disc)."""
    a = actions
    na = len(a)
    me2 = np.repeat(me[None], na, axis=0)
    u = me[1:3]
    me2[:, 0] = np.clip(me[0] - (a @ u) / max_range, 0.0, 1.0)
    me2[:, 3:5] = a
    h = len(humans)
    if h == 0:
        return me2, np.zeros((na, 0, HUMAN)), np.full(na, np.inf), np.full(na, np.inf)
    rel0 = humans[:, :2] * max_range  # (h, 2)
    v = humans[:, 2:4]
    dv = v[None, :, :] - a[:, None, :]  # (A, h, 2)
    rel1 = rel0[None] + dv
    # closest approach of rel0 + tau dv, tau in [0, 1]
    dd = (dv**2).sum(-1)
    tau = np.clip(-(rel0[None] * dv).sum(-1) / np.where(dd > 0, dd, 1.0), 0.0, 1.0)
    closest = rel0[None] + tau[..., None] * dv
    gap = (np.hypot(closest[..., 0], closest[..., 1]) - humans[None, :, 6]).min(axis=1)
    h2 = np.repeat(humans[None], na, axis=0)
    h2[..., :2] = rel1 / max_range
    d1 = np.hypot(rel1[..., 0], rel1[..., 1])
    h2[..., 5] = d1 / max_range
    return me2, h2, gap, (d1 - humans[None, :, 6]).min(axis=1)


def _mlp(x: NDArray[Any], layers: list[tuple[NDArray[Any], NDArray[Any]]],
         last_relu: bool) -> NDArray[Any]:  # fmt: skip
    for i, (w, b) in enumerate(layers):
        x = x @ w + b
        if i < len(layers) - 1 or last_relu:
            x = np.maximum(x, x.dtype.type(0.0))
    return x


@dataclass(frozen=True)
class SARLWeights:
    """SARL's value network (numpy): ``nets[name]`` its layers (w (in, out), b (out,));
    ``nets32`` the same in float32, as inference runs them."""

    nets: dict[str, list[tuple[NDArray[np.float64], NDArray[np.float64]]]]
    n_rays: int = 32
    max_range: float = 10.0
    reward: SARLReward = field(default_factory=SARLReward)
    info: dict[str, Any] = field(default_factory=dict)
    nets32: dict[str, list[tuple[NDArray[np.float32], NDArray[np.float32]]]] = field(
        init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        ins = {"mlp1": SELF + HUMAN, "mlp2": None, "attention": None,
               "mlp3": SELF + self.n_rays}  # fmt: skip
        for name in NETS:
            layers = self.nets.get(name)
            if not layers:
                raise InvalidArgumentError(f"SARL network {name!r} has no layers")
            for i, (w, b) in enumerate(layers):
                if w.ndim != 2 or b.shape != (w.shape[1],) or max(w.shape) > MAX_WIDTH:
                    raise InvalidArgumentError(f"SARL network {name!r} layer {i}: shapes "
                                               f"{w.shape} and {b.shape} do not fit")  # fmt: skip
                if i and w.shape[0] != layers[i - 1][0].shape[1]:
                    raise InvalidArgumentError(f"SARL network {name!r} layer {i} takes "
                                               f"{w.shape[0]} values; the one before gives "
                                               f"{layers[i - 1][0].shape[1]}")  # fmt: skip
                if not (np.isfinite(w).all() and np.isfinite(b).all()):
                    raise InvalidArgumentError(f"SARL network {name!r} layer {i} holds NaN "
                                               "or Inf")  # fmt: skip
        e = self.nets["mlp1"][-1][0].shape[1]
        want = {"mlp1": ins["mlp1"], "mlp2": e, "attention": 2 * e,
                "mlp3": ins["mlp3"] + self.nets["mlp2"][-1][0].shape[1]}  # fmt: skip
        for name, n_in in want.items():
            if self.nets[name][0][0].shape[0] != n_in:
                raise InvalidArgumentError(f"SARL network {name!r} takes "
                                           f"{self.nets[name][0][0].shape[0]} values; its "
                                           f"place gives {n_in}")  # fmt: skip
        for name in ("attention", "mlp3"):
            if self.nets[name][-1][0].shape[1] != 1:
                raise InvalidArgumentError(f"SARL network {name!r} must end in one value")
        object.__setattr__(self, "nets32", {
            name: [(w.astype(np.float32), b.astype(np.float32)) for w, b in layers]
            for name, layers in self.nets.items()})  # fmt: skip


def sarl_values(
    weights: SARLWeights,
    me: NDArray[np.float64],
    humans: NDArray[np.float64],
    static: NDArray[np.float64],
) -> NDArray[np.float64]:
    """Values of B states (self (B, SELF), discs (B, h, HUMAN), static (B, n_rays) or
    (n_rays,) shared): SARL's forward pass (attention over the discs, softmax weights,
    their weighted features beside the robot's state), in float32 as torch trained it.
    The first layers of ``mlp1`` and ``attention`` are split by their inputs, so that the
    parts every disc of a state shares (the robot's state, the discs' mean) are
    multiplied once a state, not once a disc: the same sums, a third of the work."""
    nets = weights.nets32
    f32 = np.float32
    b, h = humans.shape[0], humans.shape[1]
    me = np.asarray(me, dtype=f32)
    st = np.broadcast_to(np.asarray(static, dtype=f32), (b, static.shape[-1]))
    if h:
        (w1, b1), *rest1 = nets["mlp1"]
        x = (np.asarray(humans, dtype=f32) @ w1[SELF:]).reshape(b, h, -1)
        x += (me @ w1[:SELF] + b1)[:, None, :]
        e = _mlp(np.maximum(x, f32(0.0)).reshape(b * h, -1), rest1, True)  # (b h, E)
        f = _mlp(e, nets["mlp2"], False).reshape(b, h, -1)
        n_e = e.shape[1]
        e = e.reshape(b, h, n_e)
        (wa, ba), *rest_a = nets["attention"]
        y = e @ wa[:n_e] + (e.mean(axis=1) @ wa[n_e:] + ba)[:, None, :]
        s = _mlp(np.maximum(y, f32(0.0)).reshape(b * h, -1), rest_a, False).reshape(b, h)
        s = np.exp(s - s.max(axis=1, keepdims=True))
        w = s / s.sum(axis=1, keepdims=True)
        pooled = (w[..., None] * f).sum(axis=1)
    else:
        pooled = np.zeros((b, nets["mlp2"][-1][0].shape[1]), dtype=f32)
    x = np.concatenate([me, st, pooled], axis=1)
    return _mlp(x, nets["mlp3"], False)[:, 0].astype(np.float64)


def step_rewards(
    reward: SARLReward,
    me: NDArray[np.float64],
    actions: NDArray[np.float64],
    gap: NDArray[np.float64],
    end_gap: NDArray[np.float64],
    goal: NDArray[np.float64] | None,
    tolerance: float,
) -> NDArray[np.float64]:
    """The reward of each action (A, 2) of the frame (see :class:`SARLReward`: the
    proximity is the gap at the step's end ``end_gap``, a contact the gap over it
    ``gap``); ``goal`` relative to the robot in the frame (None: not within reach this
    step)."""
    r = reward.progress * (actions @ me[1:3]) - reward.time
    r = r - reward.proximity * np.clip(1.0 - end_gap / reward.near, 0.0, 1.0)
    r = np.where(gap < 0.0, -reward.contact, r)
    if goal is not None:
        there = np.hypot(goal[0] - actions[:, 0], goal[1] - actions[:, 1]) <= tolerance
        r = np.where(there & (gap >= 0.0), reward.success, r)
    return r


def wall_free(
    static: NDArray[np.float64], actions: NDArray[np.float64], radius: float, max_range: float
) -> NDArray[np.bool_]:
    """Whether each action (A, 2) of the frame stays clear of the walls by the static reading
    (scaled by the range) in its direction and the rays either side."""
    n = static.shape[0]
    speed = np.hypot(actions[:, 0], actions[:, 1])
    j = np.round(np.arctan2(actions[:, 1], actions[:, 0]) * n / (2 * np.pi)).astype(int) % n
    room = np.minimum(np.minimum(static[j], static[(j - 1) % n]), static[(j + 1) % n])
    return (speed == 0.0) | (room * max_range >= speed + radius)


class SARLAgent(Steered):
    """CrowdNav's SARL (see the module) at level ``oracle``: the route's direction from
    :class:`~copi.online.Steering`, then the best of 81 moves by one-step lookahead on the
    learnt value network. ``epsilon`` > 0 (training) moves at random that often, from
    ``rng``.

    Parameters
    ----------
    weights : str or SARLWeights
        A network copi ships (``sarl-crowd``) or a file, or weights in memory.
    """

    name = "sarl"
    sensing: Sensing = "oracle"

    def __init__(self, weights: str | SARLWeights = "sarl-crowd", *, epsilon: float = 0.0,
                 rng: np.random.Generator | None = None) -> None:  # fmt: skip
        self.weights = weights if isinstance(weights, SARLWeights) else load_sarl(
            packaged_sarl(weights))  # fmt: skip
        self.epsilon = float(epsilon)
        self.rng = rng or np.random.default_rng(0)
        self.actions = sarl_actions()
        self.velocity = np.zeros(2)
        self.last_state: tuple[Any, ...] | None = None

    def reset(self, task: Task) -> None:
        super().reset(task)
        if task.n_rays != self.weights.n_rays:
            raise InvalidArgumentError(f"SARL network of {self.weights.n_rays} rays; the task "
                                       f"has {task.n_rays}")  # fmt: skip
        self.velocity = np.zeros(2)
        self.tolerance = task.goal_tolerance

    def steer(self, obs: Observation, desired: NDArray[np.float64], reach: float
              ) -> NDArray[np.float64]:  # fmt: skip
        w = self.weights
        k, me, humans, static = sarl_state(obs, desired, reach, self.velocity, self.radius,
                                           w.max_range)  # fmt: skip
        self.last_state = (me, humans, static)
        n = obs.ranges.shape[0]
        a = self.actions
        free = wall_free(static, a, self.radius, w.max_range)
        if self.epsilon > 0.0 and self.rng.random() < self.epsilon:
            options = np.flatnonzero(free)
            best = int(self.rng.choice(options)) if len(options) else len(a) - 1
        else:
            me2, h2, gap, end_gap = lookahead_states(me, humans, a, w.max_range)
            goal = _turn(np.asarray(obs.goal, dtype=np.float64), k, n)
            close = float(np.hypot(*goal)) <= 1.0 + self.tolerance
            r = step_rewards(w.reward, me, a, gap, end_gap, goal if close else None,
                             self.tolerance)  # fmt: skip
            with _one_blas_thread():
                v = sarl_values(w, me2, h2, static)
            score = r + w.reward.gamma * v
            score = np.where(free, score, -np.inf)
            best = int(np.argmax(score)) if free.any() else len(a) - 1
            self._explained(_world(a, k, n), score, "reward + discounted value")
        move = _world(a[best : best + 1], k, n)[0]
        self.velocity = move
        return move


@functools.cache
def _blas() -> Any:
    from threadpoolctl import ThreadpoolController

    return ThreadpoolController()


def _one_blas_thread() -> Any:
    """BLAS on one thread for a decision's small products (a few hundred rows): spread
    over every core they ran 3 to 20 times slower on a busy 2-core machine, and a
    benchmark's workers would each take every core."""
    return _blas().limit(limits=1, user_api="blas")


def _world(a: NDArray[np.float64], k: int, n: int) -> NDArray[np.float64]:
    """Frame vectors (A, 2) back in the world's."""
    return _turn(a, -k, n)


SHIPPED = POLICIES / "sarl"
"""Where copi's SARL networks ship (beside the PPO and SAC policies, apart from them)."""


def packaged_sarl(name: str) -> Path:
    """The file of a SARL network copi ships, or ``name`` itself when it is a path."""
    if name.endswith(".npz") or os.sep in name:
        return Path(name)
    return SHIPPED / f"{name}.npz"


def save_sarl(weights: SARLWeights, path: str | os.PathLike[str]) -> Path:
    """Write ``weights`` to ``path`` (``.npz``, no pickle), atomically."""
    arrays: dict[str, Any] = {}
    for name in NETS:
        for i, (w, b) in enumerate(weights.nets[name]):
            arrays[f"{name}_w{i}"] = w.astype(np.float32)
            arrays[f"{name}_b{i}"] = b.astype(np.float32)
    meta = {"format": FORMAT, "version": FORMAT_VERSION, "n_rays": weights.n_rays,
            "max_range": weights.max_range, "reward": vars(weights.reward),
            "layers": {name: len(weights.nets[name]) for name in NETS},
            "info": weights.info}  # fmt: skip
    arrays["metadata"] = np.array(json.dumps(meta, sort_keys=True))
    return write_npz(path, arrays, "SARL network")


def load_sarl(path: str | os.PathLike[str]) -> SARLWeights:
    """Read a network written by :func:`save_sarl`; every other file is refused in one line
    (:class:`SARLFormatError`) saying what is wrong."""
    p = Path(path)
    members = [f"{name}_{k}{i}" for name in NETS for i in range(8) for k in "wb"]
    a = read_npz(p, [*members, "metadata"], error=SARLFormatError, what="SARL network file",
                 max_member=MAX_WIDTH * MAX_WIDTH * 8 + 4096, max_total=1 << 26)  # fmt: skip
    meta = read_metadata(a, p, fmt=FORMAT, version=FORMAT_VERSION, error=SARLFormatError,
                         what="SARL network file")  # fmt: skip
    layers = meta.get("layers")
    n_rays, reach = meta.get("n_rays"), meta.get("max_range")
    if not (isinstance(layers, dict) and all(isinstance(layers.get(x), int)
                                             and 1 <= layers[x] <= 8 for x in NETS)):  # fmt: skip
        raise SARLFormatError(f"{p}: metadata 'layers' must give 1 to 8 layers for each of "
                              f"{', '.join(NETS)}")  # fmt: skip
    if not (isinstance(n_rays, int) and 4 <= n_rays <= 1024):
        raise SARLFormatError(f"{p}: metadata 'n_rays' must be an int in 4 .. 1024")
    if not (isinstance(reach, int | float) and 0 < reach <= 1000):
        raise SARLFormatError(f"{p}: metadata 'max_range' must be a number in (0, 1000]")
    nets: dict[str, list[tuple[NDArray[np.float64], NDArray[np.float64]]]] = {}
    for name in NETS:
        nets[name] = []
        for i in range(layers[name]):
            w, b = a.get(f"{name}_w{i}"), a.get(f"{name}_b{i}")
            if w is None or b is None:
                raise SARLFormatError(f"{p}: layer {i} of network {name!r} is missing")
            if w.dtype.kind != "f" or b.dtype.kind != "f":
                raise SARLFormatError(f"{p}: layer {i} of network {name!r} is not "
                                      "floating-point numbers")  # fmt: skip
            nets[name].append((w.astype(np.float64), b.astype(np.float64)))
    try:
        reward = SARLReward(**meta.get("reward", {}))
    except (TypeError, InvalidArgumentError) as exc:
        raise SARLFormatError(f"{p}: metadata 'reward': {exc}"[:300]) from None
    info = meta.get("info", {})
    try:
        return SARLWeights(nets, int(n_rays), float(reach), reward,
                           info if isinstance(info, dict) else {})  # fmt: skip
    except InvalidArgumentError as exc:
        raise SARLFormatError(f"{p}: {exc}") from None
