"""Training SARL as CrowdNav trains it (needs the extra ``rl``: torch).

CrowdNav (``crowd_nav/train.py``, ``utils/trainer.py``, ``utils/explorer.py``) first
imitates a demonstrator: it runs ORCA for some episodes and fits the value network to
the discounted return each visited state went on to earn; then it runs the SARL policy
epsilon-greedily (epsilon falling from 0.5 to 0.1), stores each visited state with the
target ``reward + gamma * V_target(next state)`` (the target network copied every few
episodes), and after each episode fits the value network to batches drawn from that
memory. This module does the same on copi's episodes (a family's training seed, no
report's), with copi's reference planner at level ``oracle`` as the demonstrator by
default (what :mod:`copi.baselines._sarl` says SARL sees, it sees), and keeps the network
that did best on validation episodes (seed 1).
"""

from __future__ import annotations

import json
import math
import os
import time
import zipfile
from collections.abc import Callable
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from copi.baselines import SARL_HUMAN as HUMAN
from copi.baselines import SARL_MAX_HUMANS as MAX_HUMANS
from copi.baselines import SARL_NETS as NETS
from copi.baselines import SARL_SELF as SELF
from copi.baselines import SARL_WIDTHS as WIDTHS
from copi.baselines import SARLAgent, SARLReward, SARLWeights, sarl_state
from copi.core import Agent, Observation, Task
from copi.envs.local_policy import TRAINING_SEED
from copi.errors import InvalidArgumentError
from copi.online import Steering
from copi.rl._train import VALIDATION_SEED
from copi.runs import Episode

__all__ = ["SARLConfig", "SARLNet", "Transitions", "export", "record_episodes", "returns",
           "rewards", "train_sarl", "write_sarl"]

FEATURES = 1
"""The version of SARL's state features (copi.baselines.sarl_state): a cache of
demonstrations recorded under another is recorded anew."""


@dataclass(frozen=True)
class SARLConfig:
    """How SARL is trained (CrowdNav's ``train.config``, in copi's episodes)."""

    family: str = "crowd"
    demonstrator: str = "model-oracle"
    demo_episodes: int = 300
    il_epochs: int = 50
    il_lr: float = 0.001
    rl_episodes: int = 1000
    rl_lr: float = 0.0001
    """Adam's learning rates (CrowdNav's SGD at 0.01 and 0.001 fitted the demonstrations
    far more slowly here)."""
    batch: int = 100
    batches: int = 50
    """Batches fitted after each RL episode (CrowdNav's train_batches: 100)."""
    memory: int = 100_000
    epsilon: tuple[float, float, int] = (0.5, 0.1, 400)
    """Epsilon from the first to the second over the first episodes (CrowdNav's 4000)."""
    target_every: int = 50
    """Episodes between copies of the value network into the target network."""
    validate_every: int = 100
    validation_episodes: int = 60
    seed: int = 0
    reward: SARLReward = field(default_factory=SARLReward)

    def __post_init__(self) -> None:
        for k in ("demo_episodes", "il_epochs", "rl_episodes", "batch", "batches", "memory",
                  "target_every", "validate_every", "validation_episodes"):  # fmt: skip
            v = getattr(self, k)
            least = 1 if k in ("demo_episodes", "batch", "memory", "target_every") else 0
            if not (isinstance(v, int) and not isinstance(v, bool) and v >= least):
                raise InvalidArgumentError(f"{k} must be a whole number >= {least}; got {v!r}")
        e0, e1, span = self.epsilon
        if not (0 <= e1 <= 1 and 0 <= e0 <= 1 and isinstance(span, int) and span >= 0):
            raise InvalidArgumentError("epsilon must be (first, last, episodes): two numbers "
                                       f"in [0, 1] and a whole number >= 0; got {self.epsilon}")
        for k in ("il_lr", "rl_lr"):
            v = getattr(self, k)
            if not (isinstance(v, float | int) and 0 < v < 1):
                raise InvalidArgumentError(f"{k} must lie in (0, 1); got {v!r}")


@dataclass
class Transitions:
    """Visited states, padded to :data:`MAX_HUMANS` discs (``mask`` the real ones), and
    what each state's step did: its progress along the direction, the gap to the nearest
    disc at its end, and how it ended the episode (1 the goal, -1 a contact, 0 neither).
    :meth:`rewards` turns them into a :class:`SARLReward`'s rewards."""

    me: list[NDArray[np.float64]] = field(default_factory=list)
    humans: list[NDArray[np.float64]] = field(default_factory=list)
    static: list[NDArray[np.float64]] = field(default_factory=list)
    progress: list[float] = field(default_factory=list)
    gap: list[float] = field(default_factory=list)
    outcome: list[int] = field(default_factory=list)
    end: list[bool] = field(default_factory=list)
    """The episode ended after this state's step (its successor is not a state)."""

    def add(self, me: Any, humans: Any, static: Any) -> None:
        pad = np.zeros((MAX_HUMANS, HUMAN + 1))
        pad[: len(humans), :HUMAN] = humans
        pad[: len(humans), HUMAN] = 1.0
        self.me.append(me)
        self.humans.append(pad)
        self.static.append(static)
        self.progress.append(0.0)
        self.gap.append(math.inf)
        self.outcome.append(0)
        self.end.append(False)

    def arrays(self) -> dict[str, NDArray[Any]]:
        return {k: np.array(getattr(self, k)) for k in
                ("me", "humans", "static", "progress", "gap", "outcome", "end")}  # fmt: skip


def rewards(a: dict[str, NDArray[Any]], reward: SARLReward) -> NDArray[np.float64]:
    """Each recorded step's reward (see :class:`SARLReward`)."""
    r = reward.progress * a["progress"] - reward.time
    r = r - reward.proximity * np.clip(1.0 - a["gap"] / reward.near, 0.0, 1.0)
    r = np.where(a["outcome"] == 1, reward.success, r)
    return np.where(a["outcome"] == -1, -reward.contact, r)


def returns(a: dict[str, NDArray[Any]], reward: SARLReward) -> NDArray[np.float64]:
    """The discounted return each state went on to earn within its episode."""
    r = rewards(a, reward)
    g = np.zeros(len(r))
    acc = 0.0
    for i in range(len(r) - 1, -1, -1):
        acc = r[i] + (0.0 if a["end"][i] else reward.gamma * acc)
        g[i] = acc
    return g


class _Recorder(Agent):
    """Runs ``inner`` (or SARL itself) and records SARL's state at each step and what the
    step did (:class:`Transitions`)."""

    sensing = "oracle"
    steers_itself = True

    def __init__(self, inner: Agent, out: Transitions, max_range: float = 10.0) -> None:
        self.inner = inner
        self.name = inner.name
        self.out = out
        self.max_range = max_range

    def reset(self, task: Task) -> None:
        self.inner.reset(task)
        self.steering = Steering()
        self.steering.reset(task)
        self.radius = task.agent_radius
        self.velocity = np.zeros(2)
        self.before: tuple[NDArray[np.float64], NDArray[np.float64]] | None = None

    def _score_last(self, obs: Observation) -> None:
        if self.before is None:
            return
        pos, u = self.before
        assert obs.position is not None and obs.obstacles is not None
        self.out.progress[-1] = float((obs.position - pos) @ u)
        if len(obs.obstacles):
            o = obs.obstacles
            self.out.gap[-1] = float((np.hypot(*(o[:, :2] - obs.position).T) - o[:, 4]).min()
                                     - self.radius)  # fmt: skip

    def act(self, obs: Observation) -> NDArray[np.float64]:
        self._score_last(obs)
        d, reach = self.steering.aim(obs)
        _, me, humans, static = sarl_state(obs, d, reach, self.velocity, self.radius,
                                           self.max_range)  # fmt: skip
        self.out.add(me, humans, static)
        a = np.asarray(self.inner.act(obs), dtype=np.float64)
        assert obs.position is not None
        n = math.hypot(d[0], d[1])
        self.before = (obs.position.copy(), np.asarray(d) / n if n > 0 else np.zeros(2))
        self.velocity = a
        return a

    def finish(self, outcome: str) -> None:
        """The episode's last state is terminal whatever its outcome (a timeout's too, as
        CrowdNav's); its step earns the goal's bonus or the contact's penalty, and a
        timeout's last step nothing (no later observation shows what it did)."""
        self.inner.finish(outcome)
        if not self.out.end:
            return
        self.out.outcome[-1] = {"collision": -1, "success": 1}.get(outcome, 0)
        self.out.end[-1] = True


def record_episodes(
    make: Callable[[], Agent],
    episodes: range,
    family: str,
    seed: int,
    out: Transitions | None = None,
    progress: Callable[[], None] | None = None,
) -> tuple[Transitions, list[str]]:
    """Run ``make()`` on the family's episodes of ``seed`` at level ``oracle`` (the route
    as the global direction), recording SARL's states and what each step did; returns
    them and each episode's outcome."""
    out = out or Transitions()
    outcomes = []
    for k in episodes:
        ep = Episode.draw(family, k, seed)
        res = ep.run(_Recorder(make(), out), sensing="oracle")
        outcomes.append(res.outcome)
        if progress is not None:
            progress()
    return out, outcomes


def _torch() -> Any:
    import torch

    return torch


def _net_class() -> Any:
    torch = _torch()
    nn = torch.nn

    def mlp(n_in: int, widths: tuple[int, ...], last_relu: bool) -> Any:
        layers: list[Any] = []
        for i, w in enumerate(widths):
            layers.append(nn.Linear(n_in, w))
            if i < len(widths) - 1 or last_relu:
                layers.append(nn.ReLU())
            n_in = w
        return nn.Sequential(*layers)

    class _SARLNet(nn.Module):  # type: ignore[misc, name-defined]
        """SARL's value network (CrowdNav's ``ValueNetwork`` of sarl.py, masked for a
        varying number of discs)."""

        def __init__(self, n_rays: int) -> None:
            super().__init__()
            e = WIDTHS["mlp1"][-1]
            self.n_rays = n_rays
            self.mlp1 = mlp(SELF + HUMAN, WIDTHS["mlp1"], True)
            self.mlp2 = mlp(e, WIDTHS["mlp2"], False)
            self.attention = mlp(2 * e, WIDTHS["attention"], False)
            self.mlp3 = mlp(SELF + n_rays + WIDTHS["mlp2"][-1], WIDTHS["mlp3"], False)

        def forward(self, me: Any, humans: Any, static: Any) -> Any:
            b, h = humans.shape[0], humans.shape[1]
            mask = humans[..., HUMAN]
            joint = torch.cat([me[:, None, :].expand(b, h, SELF), humans[..., :HUMAN]], dim=2)
            e = self.mlp1(joint)
            f = self.mlp2(e)
            count = mask.sum(1, keepdim=True)
            g = (e * mask[..., None]).sum(1) / count.clamp(min=1.0)
            s = self.attention(torch.cat([e, g[:, None, :].expand_as(e)], dim=2))[..., 0]
            s = s.masked_fill(mask == 0, -1e9)
            w = torch.softmax(s, dim=1) * (count > 0)
            pooled = (w[..., None] * f).sum(1)
            return self.mlp3(torch.cat([me, static, pooled], dim=1))[:, 0]

    return _SARLNet


def SARLNet(n_rays: int = 32) -> Any:  # noqa: N802 - a class made on demand (torch)
    """A fresh torch value network of SARL's layout."""
    return _net_class()(n_rays)


def export(net: Any, reward: SARLReward, max_range: float = 10.0,
           info: dict[str, Any] | None = None) -> SARLWeights:  # fmt: skip
    """The numpy weights of a torch :func:`SARLNet`."""
    nets = {}
    for name in NETS:
        layers = [m for m in getattr(net, name) if hasattr(m, "weight")]
        nets[name] = [(m.weight.detach().numpy().T.astype(np.float64),
                       m.bias.detach().numpy().astype(np.float64)) for m in layers]  # fmt: skip
    return SARLWeights(nets, net.n_rays, max_range, reward, dict(info or {}))


class _Memory:
    """A replay memory of ``capacity`` states and their value targets (a ring)."""

    def __init__(self, capacity: int, data: tuple[NDArray[np.float64], ...],
                 target: NDArray[np.float64]) -> None:  # fmt: skip
        self.arrays = [np.zeros((max(1, capacity), *a.shape[1:])) for a in data]
        self.target = np.zeros(max(1, capacity))
        self.size = 0
        self.at = 0
        self.push(data, target)

    def push(self, data: tuple[NDArray[np.float64], ...], target: NDArray[np.float64]) -> None:
        cap = len(self.target)
        n = len(target)
        keep = slice(max(0, n - cap), n)  # rows in order, the oldest overwritten
        rows = (self.at + np.arange(n)[keep]) % cap
        for mem, a in zip(self.arrays, data, strict=True):
            mem[rows] = a[keep]
        self.target[rows] = target[keep]
        self.at = (self.at + n) % cap
        self.size = min(cap, self.size + n)

    def data(self) -> tuple[NDArray[np.float64], ...]:
        return tuple(a[: self.size] for a in self.arrays)


def _fit(net: Any, opt: Any, data: tuple[NDArray[np.float64], ...], target: NDArray[np.float64],
         rng: np.random.Generator, batches: int, batch: int) -> float:  # fmt: skip
    torch = _torch()
    me, humans, static = data[0], data[1], data[2]
    loss_sum = 0.0
    for _ in range(batches):
        idx = rng.integers(0, len(target), size=batch)
        pred = net(torch.as_tensor(me[idx], dtype=torch.float32),
                   torch.as_tensor(humans[idx], dtype=torch.float32),
                   torch.as_tensor(static[idx], dtype=torch.float32))  # fmt: skip
        loss = torch.nn.functional.mse_loss(pred, torch.as_tensor(target[idx],
                                                                  dtype=torch.float32))
        opt.zero_grad()
        loss.backward()
        opt.step()
        loss_sum += float(loss.detach())
    return loss_sum / max(1, batches)


def validate(weights: SARLWeights, config: SARLConfig) -> float:
    """Success rate of the greedy SARL on the family's validation episodes (seed 1)."""
    ok = 0
    for k in range(config.validation_episodes):
        ep = Episode.draw(config.family, k, VALIDATION_SEED)
        ok += ep.run(SARLAgent(weights), sensing="oracle").outcome == "success"
    return ok / max(1, config.validation_episodes)


def _demonstrations(config: SARLConfig, cache: str | os.PathLike[str] | None,
                    log: Callable[[str], None],
                    progress: Callable[[], None] | None = None) -> dict[str, NDArray[Any]]:
    """The demonstrations (:meth:`Transitions.arrays`), recorded (and kept in ``cache``, a
    plain ``.npz`` read without pickle) or read back from a cache of the same settings."""
    from copi import __version__
    from copi.methods import make_agent

    key = json.dumps({"demonstrator": config.demonstrator, "family": config.family,
                      "episodes": config.demo_episodes, "seed": TRAINING_SEED,
                      "copi": __version__, "state": [SELF, HUMAN, MAX_HUMANS, FEATURES]},
                     sort_keys=True)  # fmt: skip
    if cache is not None and Path(cache).is_file():
        try:
            with np.load(cache, allow_pickle=False) as z:
                if str(z["key"]) == key:
                    log(f"demonstrations read from {cache}")
                    return {k: z[k] for k in z.files if k != "key"}
        except (OSError, ValueError, KeyError, zipfile.BadZipFile):
            pass  # not a cache of these demonstrations: recorded anew
    demo, outcomes = record_episodes(lambda: make_agent(config.demonstrator),
                                     range(config.demo_episodes), config.family,
                                     TRAINING_SEED, progress=progress)  # fmt: skip
    log(f"{config.demonstrator}: {outcomes.count('success')} successes in "
        f"{config.demo_episodes} demonstrations")
    a = demo.arrays()
    if cache is not None:
        tmp = Path(f"{cache}.part.npz")
        np.savez(tmp, key=np.array(key), **a)  # type: ignore[arg-type]
        tmp.replace(cache)
    return a


def train_sarl(
    config: SARLConfig,
    log: Callable[[str], None] = print,
    demos: str | os.PathLike[str] | None = None,
    progress: Callable[[int, int], None] | None = None,
) -> tuple[SARLWeights, list[dict[str, float]]]:
    """Imitation, then RL (see the module); returns the best validated weights and the
    learning curve (episodes, validation success, loss). ``demos``: a file keeping the
    demonstrations between runs of the same settings; ``progress(done, total)`` counts
    the episodes run (demonstrations, then RL)."""
    from copi.methods import method_spec
    from copi.world import check_family

    check_family(config.family)
    spec = method_spec(config.demonstrator)
    if "oracle" not in spec.levels:
        raise InvalidArgumentError(f"the demonstrator must run at level oracle; "
                                   f"{config.demonstrator} runs at {', '.join(spec.levels)}")
    total = config.demo_episodes + config.rl_episodes
    done = [0]

    def step() -> None:
        done[0] += 1
        if progress is not None:
            progress(done[0], total)

    torch = _torch()
    torch.set_num_threads(1)  # batches of 100 small states: more threads only contend
    torch.manual_seed(config.seed)
    rng = np.random.default_rng(config.seed)
    gamma = config.reward.gamma
    net = SARLNet()
    info: dict[str, Any] = {"config": {k: (list(v) if isinstance(v, tuple) else v)
                       for k, v in asdict(config).items() if k != "reward"}}  # fmt: skip
    curve: list[dict[str, float]] = []
    t0 = time.perf_counter()
    # 1. imitation: the demonstrator's returns
    demo = _demonstrations(config, demos, log, step)
    if done[0] < config.demo_episodes:  # read from the cache
        done[0] = config.demo_episodes - 1
        step()
    data = (demo["me"], demo["humans"], demo["static"])
    g = returns(demo, config.reward)
    log(f"demonstrations: {len(g):,} states from {config.demo_episodes} episodes of "
        f"{config.demonstrator}, {time.perf_counter() - t0:.0f} s")
    opt = torch.optim.Adam(net.parameters(), lr=config.il_lr)
    per_epoch = max(1, len(g) // config.batch)
    loss = math.nan
    for epoch in range(config.il_epochs):
        loss = _fit(net, opt, data, g, rng, per_epoch, config.batch)
        if epoch % 10 == 9 or epoch == config.il_epochs - 1:
            log(f"imitation epoch {epoch + 1}: loss {loss:.4f}")
    best = export(net, config.reward, info=info)
    best_score = validate(best, config) if config.validation_episodes else 0.0
    curve.append({"episodes": 0, "validation": best_score, "loss": loss})
    log(f"after imitation: validation {best_score:.1%} ({time.perf_counter() - t0:.0f} s)")
    # 2. reinforcement learning, CrowdNav's: TD targets from a target network
    target = SARLNet()
    target.load_state_dict(net.state_dict())
    opt = torch.optim.Adam(net.parameters(), lr=config.rl_lr)
    # the replay memory starts with the demonstrations and their returns, as CrowdNav's
    # (one memory for both phases); RL's states overwrite the oldest as it fills
    memory = _Memory(config.memory, data, g)
    e0, e1, span = config.epsilon
    train_seed_base = 1_000_000  # episodes apart from the demonstrations'
    loss = math.nan
    for episode in range(config.rl_episodes):
        eps = e1 if episode >= span else e0 + (e1 - e0) * episode / max(1, span)
        weights = export(net, config.reward)
        agent_rng = np.random.default_rng([config.seed, episode])

        def explorer(w: SARLWeights = weights, r: Any = agent_rng, e: float = eps) -> Agent:
            return SARLAgent(w, epsilon=e, rng=r)

        k = train_seed_base + episode
        run, _ = record_episodes(explorer, range(k, k + 1), config.family, TRAINING_SEED,
                                 progress=step)  # fmt: skip
        a = run.arrays()
        me, humans, static, end = a["me"], a["humans"], a["static"], a["end"]
        reward = rewards(a, config.reward)
        with torch.no_grad():
            nxt = target(torch.as_tensor(me, dtype=torch.float32),
                         torch.as_tensor(humans, dtype=torch.float32),
                         torch.as_tensor(static, dtype=torch.float32)).numpy()  # fmt: skip
        tgt = reward.copy()
        # the episode's last state is terminal, a timeout too (as CrowdNav's)
        tgt[:-1] += gamma * nxt[1:] * (~end[:-1])
        memory.push((me, humans, static), tgt)
        if memory.size >= config.batch:
            loss = _fit(net, opt, memory.data(), memory.target[: memory.size], rng,
                        config.batches, config.batch)  # fmt: skip
        if (episode + 1) % config.target_every == 0:
            target.load_state_dict(net.state_dict())
        last = episode + 1 == config.rl_episodes
        if config.validate_every and ((episode + 1) % config.validate_every == 0 or last):
            w = export(net, config.reward, info=info)
            score = validate(w, config)
            curve.append({"episodes": episode + 1, "validation": score, "loss": loss})
            log(f"RL episode {episode + 1}: epsilon {eps:.2f}, loss {loss:.4f}, validation "
                f"{score:.1%} ({time.perf_counter() - t0:.0f} s)")
            if score > best_score:
                best, best_score = w, score
    info = {**info, "validation": best_score, "curve": curve,
            "seconds": round(time.perf_counter() - t0)}  # fmt: skip
    return SARLWeights(best.nets, best.n_rays, best.max_range, best.reward, info), curve


def write_sarl(weights: SARLWeights, curve: list[dict[str, float]],
               output: str | os.PathLike[str]) -> Path:  # fmt: skip
    """Write the network (``output``, ``.npz``), its learning curve and what trained it
    (``.json``) and the curve's figure (``.png``) beside it."""
    from copi.baselines import save_sarl
    from copi.rl._train import _curve_figure

    path = save_sarl(weights, output)
    path.with_suffix(".json").write_text(json.dumps({"curve": curve, "info": weights.info},
                                                    indent=1, default=str))  # fmt: skip
    family = weights.info.get("config", {}).get("family", "?")
    _curve_figure([{"steps": c["episodes"], "success": c["validation"]} for c in curve],
                  path.with_suffix(".png"), title=f"SARL on {family}",
                  xlabel="episodes of RL (0: after imitation)")  # fmt: skip
    return path
