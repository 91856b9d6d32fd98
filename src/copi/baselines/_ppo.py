"""A local policy learnt by deep RL (PPO), run in numpy: the learning peer of copi.

The policy lives in copi's own factorisation: the global strategy (the route at ``map``,
the goal at ``sensor``, as every method at the level gets it) gives a direction, and the
learnt local policy turns the reading and that direction into a velocity. It sees them,
as copi's templates see a context (paper §II-C), in the frame of the symmetry that turns
the direction onto the first ray: the reading is turned by the whole number of rays k
nearest the direction's angle (:func:`direction_frame`), and its velocity is turned back
by the same k rays (:func:`to_world`). What it sees (:func:`features`, the contract
training and inference share):

==============  ====  ================================================================
block           size  value
==============  ====  ================================================================
ranges          N     the reading over the sensor's range, in [0, 1], ray i of the
                      block being ray i + k of the sensor
change          N     the reading's change since the last step, clipped to +-1.5 and
                      over 1.5, in [-1, 1] (0 on the first step), turned alike
direction       2     the global direction in that frame (within half a ray of +x)
reach           1     the distance to the point aimed at, over the range, clipped to 1
==============  ====  ================================================================

A policy of the second observation, ``copi-local-v3`` (:func:`features_v3`), is learnt at
one sensing level and sees what that level gives, in the same frame:

==============  ==========  ==========================================================
block           size        value
==============  ==========  ==========================================================
ranges          N           the reading, over the range
unexplained     N (``map``) what the static reading says lies beyond each hit, over the
                            range, 0 where the static world explains the hit: the hits of
                            moving things (absent at ``sensor``, which has no map)
change          (F - 1) N   the reading's change over each of the last F - 1 steps, most
                            recent first, clipped to +-1.5 and over 1.5 (0 before the
                            episode began): F readings stacked
velocity        2           the agent's own last velocity (what it commanded), in the frame
direction       2           as above
reach           1           as above
==============  ==========  ==========================================================

Its action is the network's mean output, clipped to [-1, 1] per component (PPO's; a SAC
actor's, squashed by tanh: the policy's ``output``) and to norm 1, turned back to the
world's frame. A ``compass`` policy (a classifier, cloned from a demonstrator's moves:
``copi rl train --algo clone``) instead scores N + 1 moves, a step along each ray of its
frame or none, and takes the best (:func:`compass_move`).
Training (``copi rl train``, the optional extra ``rl``: Stable-Baselines3 on torch)
exports the actor's weights to an ``.npz`` of plain arrays (:func:`save_policy`), read
here without torch and without pickle (:func:`load_policy`, validated as capabilities
are). ``ppo-guard`` adds compass-guard's hand-written guard as a shield: the 16 compass
moves are offered, and the guard picks the safe one nearest the policy's velocity.
"""

from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numba
import numpy as np
from numpy.typing import NDArray

from copi._files import write_npz
from copi._npz import read_metadata, read_npz
from copi.baselines._common import Steered
from copi.baselines._compass import compass_move
from copi.core import Observation, Task
from copi.errors import CopiError, InvalidArgumentError
from copi.online import kernels

__all__ = [
    "MAX_LAYERS",
    "MAX_WIDTH",
    "OBSERVATION",
    "OBSERVATION_V3",
    "PPOAgent",
    "PolicyFormatError",
    "PolicyWeights",
    "check_layout",
    "compass_move",
    "direction_frame",
    "features",
    "features_v3",
    "load_policy",
    "packaged_policy",
    "save_policy",
    "to_world",
]

FORMAT = "copi-policy"
FORMAT_VERSION = 1
OBSERVATION = "copi-local-v2"
"""The first observation layout above (ranges, change, direction, reach, in the
direction's frame)."""
OBSERVATION_V3 = "copi-local-v3"
"""The second (:func:`features_v3`): one level's reading, F readings stacked, the agent's
own velocity."""
OBSERVATIONS = (OBSERVATION, OBSERVATION_V3)
MAX_FRAMES = 16
"""Most readings a ``copi-local-v3`` policy stacks."""
CHANGE_CLIP = 1.5
"""Largest change of a ray in one step the observation keeps (as contexts that see
motion clip it)."""
OUTPUTS = ("clip", "tanh", "compass")
"""How a policy's last layer becomes a velocity: its mean clipped to [-1, 1] (PPO's
Gaussian policy) or squashed by tanh (SAC's), then to norm 1; or (``compass``) the best of
N + 1 scores, one per ray of the frame and one for standing still (:func:`compass_move`)."""
MAX_LAYERS = 8
MAX_WIDTH = 1024
MAX_WEIGHT = 1e4
"""Largest absolute weight a file may hold (trained weights stay within tens)."""
POLICIES = Path(__file__).resolve().parents[1] / "data" / "rl"
"""The trained policies copi ships (their training commands in the README beside them)."""


class PolicyFormatError(CopiError):
    """A policy file is missing, truncated, foreign, of another observation, or tampered."""


def observation_size(n_rays: int, observation: str = OBSERVATION, level: str = "sensor",
                     frames: int = 2) -> int:  # fmt: skip
    """The length of a policy's observation (see the module)."""
    if observation == OBSERVATION:
        return 2 * n_rays + 3
    return n_rays * (1 + (level != "sensor") + frames - 1) + 5


def check_layout(observation: Any, frames: Any, levels: tuple[str, ...] | None = None) -> None:
    """Refuse, in one line, an observation that is not one of :data:`OBSERVATIONS`, a
    number of readings it cannot stack, or (``levels``: those a policy is learnt at) a
    ``copi-local-v3`` policy learnt at more than one level."""
    if observation not in OBSERVATIONS:
        raise InvalidArgumentError(f"observation must be one of {', '.join(OBSERVATIONS)}; "
                                   f"got {observation!r}")  # fmt: skip
    if isinstance(frames, bool) or not isinstance(frames, int) or not (
        2 <= frames <= MAX_FRAMES and (observation == OBSERVATION_V3 or frames == 2)
    ):
        raise InvalidArgumentError(f"frames must be an int in 2 .. {MAX_FRAMES} (2 for "
                                   f"{OBSERVATION}); got {frames!r}")  # fmt: skip
    if observation == OBSERVATION_V3 and levels is not None and len(set(levels)) != 1:
        raise InvalidArgumentError(f"a {OBSERVATION_V3} policy is learnt at one level (it sees "
                                   f"that level's reading); got levels "
                                   f"{', '.join(levels)}")  # fmt: skip


def direction_frame(direction: Any, n_rays: int) -> int:
    """k: the whole number of rays nearest the angle of ``direction`` (0 for none).

    Examples
    --------
    >>> direction_frame([0.0, 1.0], 32), direction_frame([-1.0, -0.01], 32)
    (8, 16)
    """
    dx, dy = float(direction[0]), float(direction[1])
    if dx == 0.0 and dy == 0.0:
        return 0
    return int(round(math.atan2(dy, dx) * n_rays / (2 * math.pi))) % n_rays


def to_world(v: NDArray[np.float64], k: int, n_rays: int) -> NDArray[np.float64]:
    """A velocity of the policy's frame (:func:`direction_frame` ``k``) in the world's."""
    a = 2 * math.pi * k / n_rays
    c, s = math.cos(a), math.sin(a)
    return np.array([c * v[0] - s * v[1], s * v[0] + c * v[1]])


def features(
    ranges: Any,
    previous: Any,
    direction: Any,
    reach: float,
    max_range: float,
    out: NDArray[np.float64] | None = None,
) -> NDArray[np.float64]:
    """The policy's observation (see the module), shape (2 N + 3,), in the frame of
    ``direction_frame(direction, N)``.

    Examples
    --------
    >>> f = features([5.0, 6.0, 7.0, 8.0], None, [0.0, 4.0], 20.0, 10.0)
    >>> f.round(2).tolist()   # direction along ray 1: the reading starts at ray 1
    [0.6, 0.7, 0.8, 0.5, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 1.0]
    """
    r = np.asarray(ranges, dtype=np.float64)
    n = r.shape[0]
    x = np.empty(2 * n + 3) if out is None else out
    k = direction_frame(direction, n)
    x[: n - k] = r[k:]
    x[n - k : n] = r[:k]
    x[:n] /= max_range
    if previous is None:
        x[n : 2 * n] = 0.0
    else:
        change = np.clip(r - np.asarray(previous, dtype=np.float64), -CHANGE_CLIP,
                         CHANGE_CLIP) / CHANGE_CLIP  # fmt: skip
        x[n : 2 * n - k] = change[k:]
        x[2 * n - k : 2 * n] = change[:k]
    _aim_into(x, 2 * n, direction, k, n, reach, max_range)
    return x


def _aim_into(x: NDArray[np.float64], m: int, direction: Any, k: int, n: int, reach: float,
              max_range: float) -> None:  # fmt: skip
    """The last blocks of both observations at ``x[m:m + 3]``: the direction in the frame
    of ``k`` rays (0 for none) and the reach over the range, clipped to 1."""
    dx, dy = float(direction[0]), float(direction[1])
    if dx != 0.0 or dy != 0.0:
        a = math.atan2(dy, dx) - 2 * math.pi * k / n
        x[m] = math.cos(a)
        x[m + 1] = math.sin(a)
    else:
        x[m] = x[m + 1] = 0.0
    x[m + 2] = min(1.0, max(0.0, float(reach)) / max_range)


def features_v3(
    ranges: Any,
    history: Any,
    static: Any,
    velocity: Any,
    direction: Any,
    reach: float,
    max_range: float,
    frames: int,
) -> NDArray[np.float64]:
    """The ``copi-local-v3`` observation (see the module), in the frame of
    ``direction_frame(direction, N)``: ``history`` the earlier readings, most recent
    first (those missing count as no change), ``static`` the static reading at ``map``
    (None at ``sensor``: no unexplained block), ``velocity`` the agent's last commanded
    velocity in the world's axes.

    Examples
    --------
    >>> f = features_v3([5.0, 6.0, 7.0, 8.0], [[5.0, 7.5, 7.0, 8.0]], [5.0, 9.0, 7.0, 8.0],
    ...                 [0.0, 1.0], [0.0, 4.0], 20.0, 10.0, 2)
    >>> f.round(2).tolist()   # turned by one ray: the reading starts at ray 1
    [0.6, 0.7, 0.8, 0.5, 0.3, 0.0, 0.0, 0.0, -1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 1.0, 0.0, 1.0]
    """
    r = np.asarray(ranges, dtype=np.float64)
    n = r.shape[0]
    k = direction_frame(direction, n)
    blocks = [r / max_range]
    if static is not None:
        blocks.append(np.maximum(np.asarray(static, dtype=np.float64) - r, 0.0) / max_range)
    newer = r
    for j in range(frames - 1):
        if j < len(history) and history[j] is not None:
            older = np.asarray(history[j], dtype=np.float64)
            blocks.append(np.clip(newer - older, -CHANGE_CLIP, CHANGE_CLIP) / CHANGE_CLIP)
            newer = older
        else:
            blocks.append(np.zeros(n))
    x = np.empty(n * len(blocks) + 5)
    for i, block in enumerate(blocks):
        x[i * n : (i + 1) * n] = np.roll(block, -k)
    a = 2 * math.pi * k / n
    c, s = math.cos(a), math.sin(a)
    vx, vy = float(velocity[0]), float(velocity[1])
    m = n * len(blocks)
    x[m] = c * vx + s * vy  # the velocity turned back by the frame's angle
    x[m + 1] = -s * vx + c * vy
    _aim_into(x, m + 2, direction, k, n, reach, max_range)
    return x


@dataclass(frozen=True, eq=False)
class PolicyWeights:
    """An actor network: ``len(layers)`` dense layers, tanh between them (none after the
    last), from the observation to the mean velocity."""

    layers: tuple[tuple[NDArray[np.float64], NDArray[np.float64]], ...]
    """(W of shape (out, in), b of shape (out,)) per layer."""
    n_rays: int = 32
    max_range: float = 10.0
    info: dict[str, Any] = field(default_factory=dict)
    """How it was trained (JSON-able): algorithm, families, levels, steps, seed, command."""
    observation: str = OBSERVATION
    """What it sees: :data:`OBSERVATION` or :data:`OBSERVATION_V3` (see the module)."""
    level: str = "sensor"
    """The sensing level a ``copi-local-v3`` policy was learnt at and sees ("sensor" or
    "map"); a ``copi-local-v2`` policy sees the same at every level."""
    frames: int = 2
    """Readings a ``copi-local-v3`` policy stacks (the present and ``frames - 1``
    before)."""
    output: str = "clip"
    """How the last layer becomes a velocity (:data:`OUTPUTS`): ``clip`` (PPO) or
    ``tanh`` (SAC)."""

    def __post_init__(self) -> None:
        check_layout(self.observation, self.frames)
        if self.output not in OUTPUTS:
            raise InvalidArgumentError(f"a policy's output is one of {', '.join(OUTPUTS)}; got "
                                       f"{self.output!r}")  # fmt: skip
        if self.level not in ("sensor", "map"):
            raise InvalidArgumentError(f"a policy's level is sensor or map; got {self.level!r}")
        _check_layers(self.layers, self.n_rays, "the policy", self.size, self.outputs)
        flat = np.concatenate([np.r_[w.T.ravel(), b] for w, b in self.layers])  # input-major
        shapes = np.array([w.shape for w, _ in self.layers], dtype=np.int64)
        object.__setattr__(self, "_flat", np.ascontiguousarray(flat, dtype=np.float64))
        object.__setattr__(self, "_shapes", shapes)
        width = int(max(max(w.shape) for w, _ in self.layers))
        # the forward pass's scratch rows, allocated once (a decision is a few us)
        object.__setattr__(self, "_buf", np.empty((2, width)))

    @property
    def outputs(self) -> int:
        """The values its last layer gives: a velocity (2), or a ``compass`` policy's score
        of each move (one a ray, and standing still)."""
        return self.n_rays + 1 if self.output == "compass" else 2

    @property
    def size(self) -> int:
        """The length of the observation it takes."""
        return observation_size(self.n_rays, self.observation, self.level, self.frames)

    def act(self, x: NDArray[np.float64]) -> NDArray[np.float64]:
        """The velocity for one observation (mean action, clipped or squashed into
        [-1, 1] as :attr:`output` says, then to norm 1)."""
        x = np.asarray(x, dtype=np.float64)
        if x.shape != (self.layers[0][0].shape[1],):
            raise ValueError(f"an observation of shape ({self.layers[0][0].shape[1]},) was "
                             f"expected; got {x.shape}")  # fmt: skip
        out = np.empty(self.outputs)
        _forward(self._flat, self._shapes, x, self._buf, out,  # type: ignore[attr-defined]
                 OUTPUTS.index(self.output))  # fmt: skip
        if self.output == "compass":
            return compass_move(out, x, self.n_rays, self.max_range)
        return out

    def act_batch(self, x: NDArray[np.float64]) -> NDArray[np.float64]:
        """Velocities for observations (B, 2 N + 3) at once, shape (B, 2). A ``compass``
        policy's, one at a time by :meth:`act`: its choice is an argmax, which the fixed
        order of :meth:`act`'s sums keeps the same on every processor (a BLAS product's
        order is its own)."""
        if self.output == "compass":
            return np.array([self.act(r) for r in np.asarray(x, dtype=np.float64)]).reshape(-1, 2)
        h = np.asarray(x, dtype=np.float64)
        for i, (w, b) in enumerate(self.layers):
            h = h @ w.T + b
            if i < len(self.layers) - 1:
                np.tanh(h, out=h)
        if self.output == "tanh":
            np.tanh(h, out=h)
        else:
            np.clip(h, -1.0, 1.0, out=h)
        norm = np.hypot(h[:, 0], h[:, 1])
        big = norm > 1.0
        h[big] /= norm[big, None]
        return h


@numba.njit(cache=True)
def _forward(flat, shapes, x, buf, out, mode):  # type: ignore[no-untyped-def]
    """The actor's forward pass over packed layers (numba: a Python loop of numpy calls
    costs ~2 us a layer, over the 10 us a decision may take). Each layer's weights are
    packed input-major (W transposed), so that one input updates every unit at once:
    the loop over units vectorises while each unit's sum keeps its order (inputs 0, 1,
    ..., then the bias), the same on every processor (no fastmath). ``mode`` (the
    index in :data:`OUTPUTS`): 0 the velocity clipped (PPO's), 1 through tanh (SAC's),
    2 the last layer's values as they are (a ``compass`` policy's scores)."""
    m = x.shape[0]
    a = buf[0]
    b = buf[1]
    a[:m] = x
    off = 0
    nl = shapes.shape[0]
    for li in range(nl):
        rows = shapes[li, 0]
        cols = shapes[li, 1]
        bias = off + rows * cols
        for i in range(rows):
            b[i] = 0.0
        for j in range(cols):
            aj = a[j]
            w = flat[off + j * rows : off + (j + 1) * rows]
            for i in range(rows):
                b[i] += w[i] * aj
        for i in range(rows):
            s = flat[bias + i] + b[i]
            b[i] = math.tanh(s) if li < nl - 1 else s
        off += rows * cols + rows
        a, b = b, a
    if mode == 2:
        for i in range(out.shape[0]):
            out[i] = a[i]
        return
    if mode == 1:
        vx = math.tanh(a[0])
        vy = math.tanh(a[1])
    else:
        vx = min(1.0, max(-1.0, a[0]))
        vy = min(1.0, max(-1.0, a[1]))
    n = math.hypot(vx, vy)
    if n > 1.0:
        vx /= n
        vy /= n
    out[0] = vx
    out[1] = vy


def _check_layers(layers: Any, n_rays: int, where: str, width: int, outputs: int = 2) -> None:
    if not isinstance(layers, tuple) or not 2 <= len(layers) <= MAX_LAYERS:
        got = len(layers) if isinstance(layers, tuple) else type(layers).__name__
        raise InvalidArgumentError(f"{where} must have 2 .. {MAX_LAYERS} layers; got {got}")
    for i, (w, b) in enumerate(layers):
        if w.ndim != 2 or b.shape != (w.shape[0],):
            raise InvalidArgumentError(
                f"{where}: layer {i} has weights {w.shape} and biases {b.shape}; expected "
                "(out, in) and (out,)"
            )
        if w.shape[1] != width:
            what = f"the observation's {width} values ({n_rays} rays)" if i == 0 \
                else f"layer {i - 1}'s {width} outputs"  # fmt: skip
            raise InvalidArgumentError(
                f"{where}: layer {i} takes {w.shape[1]} inputs; expected {what}"
            )
        if not 1 <= w.shape[0] <= MAX_WIDTH:
            raise InvalidArgumentError(f"{where}: layer {i} has {w.shape[0]} units; at most "
                                       f"{MAX_WIDTH}")  # fmt: skip
        for arr in (w, b):
            if not (np.isfinite(arr).all() and (np.abs(arr) <= MAX_WEIGHT).all()):
                raise InvalidArgumentError(
                    f"{where}: layer {i} holds weights that are not finite or beyond "
                    f"+-{MAX_WEIGHT:g}, which no training yields"
                )
        width = w.shape[0]
    if width != outputs:
        what = "a velocity is 2" if outputs == 2 else \
            f"a compass policy scores {outputs} moves ({n_rays} rays and standing still)"
        raise InvalidArgumentError(f"{where}: the last layer gives {width} values; {what}")


def save_policy(policy: PolicyWeights, path: str | os.PathLike[str]) -> Path:
    """Write ``policy`` to ``path`` (``.npz``, no pickle), atomically."""
    arrays: dict[str, Any] = {}
    for i, (w, b) in enumerate(policy.layers):
        # a network trained in float32 (torch's) is stored in float32: half the bytes, the
        # same numbers (read back as float64, exactly)
        for key, arr in ((f"w{i}", w), (f"b{i}", b)):
            single = arr.astype(np.float32)
            arrays[key] = single if np.array_equal(single, arr) else arr
    meta = {"format": FORMAT, "version": FORMAT_VERSION, "observation": policy.observation,
            "level": policy.level, "frames": policy.frames, "output": policy.output,
            "layers": len(policy.layers), "n_rays": policy.n_rays,
            "max_range": policy.max_range, "activation": "tanh", "info": policy.info}  # fmt: skip
    arrays["metadata"] = np.array(json.dumps(meta, sort_keys=True))
    return write_npz(path, arrays, "policy")


def load_policy(path: str | os.PathLike[str]) -> PolicyWeights:
    """Read a policy written by :func:`save_policy`; every other file is refused in one
    line (:class:`PolicyFormatError`) saying what is wrong."""
    p = Path(path)
    members = [f"{k}{i}" for i in range(MAX_LAYERS) for k in "wb"] + ["metadata"]
    a = read_npz(p, members, error=PolicyFormatError, what="policy file",
                 max_member=MAX_WIDTH * MAX_WIDTH * 8 + 4096, max_total=1 << 28)  # fmt: skip
    meta = read_metadata(a, p, fmt=FORMAT, version=FORMAT_VERSION, error=PolicyFormatError,
                         what="policy file")  # fmt: skip
    observation = meta.get("observation")
    if observation not in OBSERVATIONS:
        raise PolicyFormatError(
            f"{p}: a policy of observation {observation!r}; this copi feeds "
            f"{' or '.join(map(repr, OBSERVATIONS))}"
        )
    level, frames = meta.get("level", "sensor"), meta.get("frames", 2)
    if level not in ("sensor", "map"):
        raise PolicyFormatError(f"{p}: metadata 'level' must be sensor or map; got {level!r}")
    if not (isinstance(frames, int) and 2 <= frames <= MAX_FRAMES):
        raise PolicyFormatError(f"{p}: metadata 'frames' must be an int in 2 .. {MAX_FRAMES}")
    output = meta.get("output", "clip")  # absent from the files of PPO before SAC came
    if output not in OUTPUTS:
        raise PolicyFormatError(f"{p}: metadata 'output' must be one of {', '.join(OUTPUTS)}; got "
                                f"{output!r}"[:200])  # fmt: skip
    n_layers, n_rays, reach = meta.get("layers"), meta.get("n_rays"), meta.get("max_range")
    if not (isinstance(n_layers, int) and 2 <= n_layers <= MAX_LAYERS):
        raise PolicyFormatError(f"{p}: metadata 'layers' must be an int in 2 .. {MAX_LAYERS}")
    if not (isinstance(n_rays, int) and 4 <= n_rays <= 1024):
        raise PolicyFormatError(f"{p}: metadata 'n_rays' must be an int in 4 .. 1024")
    if not (isinstance(reach, int | float) and 0 < reach <= 1000):
        raise PolicyFormatError(f"{p}: metadata 'max_range' must be a number in (0, 1000]")
    if meta.get("activation") != "tanh":
        raise PolicyFormatError(f"{p}: activation {meta.get('activation')!r}; copi runs tanh")
    layers = []
    for i in range(n_layers):
        if f"w{i}" not in a or f"b{i}" not in a:
            raise PolicyFormatError(f"{p}: layer {i} of {n_layers} is missing")
        w, b = a[f"w{i}"], a[f"b{i}"]
        if w.dtype.kind != "f" or b.dtype.kind != "f":
            raise PolicyFormatError(f"{p}: layer {i} is not floating-point numbers")
        layers.append((w.astype(np.float64), b.astype(np.float64)))
    info = meta.get("info", {})
    try:
        return PolicyWeights(tuple(layers), int(n_rays), float(reach),
                             info if isinstance(info, dict) else {}, observation, level,
                             frames, output)  # fmt: skip
    except InvalidArgumentError as exc:
        raise PolicyFormatError(f"{p}: {exc}") from None


def packaged_policy(name: str) -> Path:
    """The file of a policy copi ships (``ppo-mix``, ``ppo-star``, ...; ``seeds/NAME``: a
    shipped policy of another training seed), or ``name`` itself when it is a path."""
    if name.endswith(".npz") or (os.sep in name and not name.startswith("seeds/")):
        return Path(name)
    return POLICIES / f"{name}.npz"


class PPOAgent(Steered):
    """A PPO policy as a local method (level ``sensor``): the global direction of its
    level from :class:`~copi.online.Steering`, then the learnt network. Nothing
    hand-written but, with ``guard > 0``, compass-guard's guard as a shield.

    Parameters
    ----------
    weights : str
        A policy copi ships (``ppo-mix``: trained on all five families) or a file.
    guard : float
        The shield's reach (0: none; ``ppo-guard``: compass-guard's 1.05).
    policy : PolicyWeights, optional
        A policy in memory instead (e.g. one being trained).
    """

    name = "ppo"
    sensing = "sensor"

    def __init__(
        self, *, weights: str = "ppo-mix", guard: float = 0.0, policy: PolicyWeights | None = None
    ) -> None:
        if not (math.isfinite(guard) and guard >= 0):
            raise InvalidArgumentError(f"guard must be a finite number >= 0; got {guard!r}")
        self.weights = weights
        self.guard = float(guard)
        self.policy = policy if policy is not None else load_policy(packaged_policy(weights))
        a = 2 * np.pi * np.arange(16) / 16
        self._cand = np.ascontiguousarray(np.column_stack([np.cos(a), np.sin(a)])[None])
        self._ok = np.ones((1, 16), dtype=np.bool_)
        self._out = np.empty(5)
        self._x = np.empty(self.policy.size)
        self._v3 = self.policy.observation == OBSERVATION_V3
        # a copi-local-v3 policy sees its own level's reading: it runs at that level
        self.sensing = self.policy.level if self._v3 else "sensor"  # type: ignore[assignment]

    def reset(self, task: Task) -> None:
        super().reset(task)
        if task.n_rays != self.policy.n_rays:
            raise InvalidArgumentError(
                f"the policy was trained for {self.policy.n_rays} rays; the sensor has "
                f"{task.n_rays}"
            )
        self._prev: NDArray[np.float64] | None = None
        self._history: list[NDArray[np.float64]] = []  # earlier readings, newest first (v3)
        self._velocity = np.zeros(2)
        self._node = np.zeros((task.n_rays, 1))  # one node at 0, transposed (the kernels' layout)
        self._no_static = np.full(task.n_rays, np.inf)

    def steer(
        self, obs: Observation, desired: NDArray[np.float64], reach: float
    ) -> NDArray[np.float64]:
        if self._v3:
            p = self.policy
            x = features_v3(obs.ranges, self._history, obs.static if p.level == "map" else None,
                            self._velocity, desired, reach, p.max_range, p.frames)  # fmt: skip
            self._history = [np.array(obs.ranges, dtype=np.float64), *self._history][: p.frames - 1]
            v = self._steer_from(obs, x, desired, reach)
            self._velocity = v.copy()
            return v
        x = features(obs.ranges, self._prev, desired, reach, self.policy.max_range, self._x)
        self._prev = np.array(obs.ranges, dtype=np.float64)
        return self._steer_from(obs, x, desired, reach)

    def _steer_from(
        self, obs: Observation, x: NDArray[np.float64], desired: NDArray[np.float64], reach: float
    ) -> NDArray[np.float64]:
        v = to_world(self.policy.act(x), direction_frame(desired, self.policy.n_rays),
                     self.policy.n_rays)  # fmt: skip
        self._explained(v[None], [0.0], "the policy's action (its mean; no candidates)"
                        + (", then the guard's shield" if self.guard > 0 else ""))  # fmt: skip
        if self.guard <= 0:
            return v
        static = self._no_static if obs.static is None else obs.static
        speed = math.hypot(v[0], v[1])
        if speed < 1e-9:
            return v
        out = self._out
        kernels.decide(
            np.asarray(obs.ranges, dtype=np.float64), static, self._node, self._cand, self._ok,
            v[0], v[1], max(reach, 1.0) * speed, self.guard, self.cos, self.sin,
            self.max_range, out,
        )  # fmt: skip
        return out[:2].copy()
