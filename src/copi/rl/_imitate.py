"""An imitation warm start for PPO (:func:`copi.rl.train` with ``imitate``): the policy
first clones a registered method's moves, then PPO improves on it (the recipe of DRL-VO
and of CrowdNav's value networks: imitation, then RL).

The demonstrator runs at the policy's own level, told exactly what the runner tells a
method there (the reading, the goal, and at ``map`` the position, the world and the
static reading; the level's global direction), so the policy learns nothing its level
does not know. Its moves are turned into the policy's frame (:func:`copi.baselines.to_world`
backwards) and paired with the observation the policy sees in the same state.

DAgger (Ross et al. 2011): the first round's episodes are driven by the demonstrator;
each later round's by the policy cloned so far, the demonstrator still labelling every
state (it is asked at every step of every round, so whatever it remembers from step to
step is its own run's), and the policy is cloned again on everything gathered. A cloned
policy that meets states its demonstrator never led it into learns what to do there.

A clone on its own (:func:`train_clone`, ``copi rl train --algo clone``) is no RL at all:
a classifier of the demonstrator's moves. A move of compass-guard is a step along one of
its 16 compass directions, which in the policy's frame (turned by whole rays) is one of
the N rays; the clone scores N + 1 classes (a ray each, and standing still) by
cross-entropy and takes the best (a ``compass`` policy, :func:`copi.baselines.compass_move`),
where PPO's warm start regresses the move's two components.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import NDArray

from copi.baselines import PolicyWeights, compass_move, direction_frame, to_world
from copi.core import Observation
from copi.envs.local_policy import LocalPolicyEnv
from copi.errors import InvalidArgumentError
from copi.methods import make_agent, method_spec
from copi.runs import make_task, velocity_of

__all__ = ["check_demonstrator", "clone", "compass_classes", "demonstrate", "train_clone",
           "warm_start"]


def check_demonstrator(method: str, level: str) -> None:
    """One line unless ``method`` can demonstrate at ``level`` (a registered method that
    needs no capabilities file and runs at that level)."""
    try:
        spec = method_spec(method)
    except InvalidArgumentError as exc:
        raise InvalidArgumentError(f"the demonstrator: {exc}") from None
    if spec.capabilities is not None:
        raise InvalidArgumentError(
            f"the demonstrator must need no capabilities file; {method!r} needs the "
            f"{spec.capabilities} preset's"
        )
    agent = make_agent(method, None)
    levels = ("sensor", "map", "oracle")
    if levels.index(agent.sensing) > levels.index(level):
        raise InvalidArgumentError(f"the demonstrator must run at level {level} (the "
                                   f"policy's); {method!r} needs {agent.sensing}")  # fmt: skip


def demonstrate(
    env: LocalPolicyEnv,
    method: str,
    episodes: int,
    *,
    act: Callable[[NDArray[np.float32]], NDArray[np.float64]] | None = None,
    progress: Callable[[int], None] | None = None,
) -> tuple[NDArray[np.float32], NDArray[np.float32], float]:
    """``episodes`` episodes of ``env`` (reset in turn from its own generator), each state
    labelled with ``method``'s move in the policy's frame; driven by the demonstrator, or
    by ``act`` (the policy's move for an observation) when given. Returns the
    observations (T, size), the demonstrator's moves (T, 2) and the driver's success."""
    level = env.levels[0]
    check_demonstrator(method, level)
    if len(env.levels) != 1 or env.task != "navigation":
        raise InvalidArgumentError("imitation needs navigation episodes at one level")
    rank = ("sensor", "map", "oracle").index(level)
    n = 0
    xs: list[NDArray[np.float32]] = []
    ys: list[NDArray[np.float64]] = []
    wins = 0
    agent = make_agent(method, None)
    for e in range(episodes):
        x, _ = env.reset()
        sim = env.sim
        agent.reset(make_task(sim, level))  # type: ignore[arg-type]
        done = False
        step = 0
        info: dict[str, Any] = {}
        while not done:
            step += 1
            d = env.direction
            norm = math.hypot(d[0], d[1])
            obs = Observation(
                ranges=sim.ranges.copy(), goal=sim.goal - sim.position,
                position=sim.position.copy() if rank >= 1 else None,
                static=sim.sensor.scan(sim.world, sim.position) if rank >= 1 else None,
                direction=d / norm if norm > 0 else np.zeros(2), reach=env.reach,
            )  # fmt: skip
            v = velocity_of(agent.act(obs), agent, step)
            k = direction_frame(d, sim.sensor.n_rays)
            label = to_world(v, (-k) % sim.sensor.n_rays, sim.sensor.n_rays)
            xs.append(x)
            ys.append(label)
            n += 1
            move = label if act is None else act(x)
            x, _, terminated, truncated, info = env.step(move)
            sim = env.sim
            done = terminated or truncated
        wins += bool(info.get("is_success"))
        if progress is not None:
            progress(e + 1)
    return (np.asarray(xs, dtype=np.float32).reshape(n, -1),
            np.asarray(ys, dtype=np.float32).reshape(n, 2), wins / max(episodes, 1))  # fmt: skip


def _actor_mean(policy: Any, x: Any) -> Any:
    """The mean action of Stable-Baselines3 PPO ``policy``'s actor for observations ``x``
    (a tensor, one row each): what :func:`clone` fits and the clone drives by."""
    features = policy.extract_features(x, policy.pi_features_extractor)
    return policy.action_net(policy.mlp_extractor.forward_actor(features))


def clone(
    policy: Any,
    x: NDArray[np.float32],
    y: NDArray[np.float32],
    *,
    epochs: int,
    batch_size: int = 256,
    learning_rate: float = 1e-3,
    seed: int = 0,
) -> list[float]:
    """Fit the mean action of Stable-Baselines3's ``policy`` (PPO's actor: its policy
    network and action layer; not its spread, nor its critic) to the moves ``y`` of the
    observations ``x`` by mean squared error, Adam, ``epochs`` passes in a shuffled order
    from ``seed``. Returns each pass's mean loss."""
    import torch

    params = [*policy.mlp_extractor.policy_net.parameters(), *policy.action_net.parameters()]
    return _fit(params, lambda xb, yb: torch.nn.functional.mse_loss(_actor_mean(policy, xb), yb),
                x, np.clip(y, -1.0, 1.0), epochs=epochs, seed=seed, batch_size=batch_size,
                learning_rate=learning_rate)  # fmt: skip


def _fit(params: Any, loss_of: Callable[[Any, Any], Any], x: Any, target: Any, *, epochs: int,
         seed: int, batch_size: int, learning_rate: float) -> list[float]:  # fmt: skip
    """Minimise ``loss_of(x_batch, target_batch)`` over ``params`` by Adam, ``epochs``
    passes over ``x`` in a shuffled order from ``seed``; each pass's mean loss."""
    import torch

    if len(x) == 0:
        raise InvalidArgumentError("nothing to imitate: no demonstrations")
    opt = torch.optim.Adam(params, lr=learning_rate)
    xt = torch.as_tensor(x)
    tt = torch.as_tensor(target)
    gen = torch.Generator().manual_seed(int(seed))
    losses = []
    for _ in range(int(epochs)):
        order = torch.randperm(len(xt), generator=gen)
        total = 0.0
        for i in range(0, len(xt), batch_size):
            idx = order[i : i + batch_size]
            loss = loss_of(xt[idx], tt[idx])
            opt.zero_grad()
            loss.backward()
            opt.step()
            total += loss.item() * len(idx)
        losses.append(total / len(xt))
    return losses


def _demonstration_env(config: Any) -> LocalPolicyEnv:
    """The environment of ``config``'s demonstrations, reset apart from the training
    environments' seeds."""
    env = LocalPolicyEnv(config.families, levels=config.levels, reward=config.reward,
                         max_steps=config.max_steps, observation=config.observation,
                         frames=config.frames, episodes=config.episodes)  # fmt: skip
    env.reset(seed=config.seed * 1000 + 999)
    return env


def _dagger(env: LocalPolicyEnv, config: Any, act: Callable[[NDArray[np.float32]], Any],
            progress: Callable[[str, int, int], None] | None) -> Any:  # fmt: skip
    """DAgger's rounds (see the module): for each, (round, episodes, observations, the
    demonstrator's moves, the driver's success): the demonstrator drives the first,
    ``act`` the later ones (half as many episodes); ``progress(stage, done, total)``."""
    for r in range(config.dagger_rounds + 1):
        episodes = config.imitation_episodes if r == 0 else max(1, config.imitation_episodes // 2)
        stage = f"imitation: {config.imitate} drives" if r == 0 else f"DAgger round {r}"

        def tick(done: int, stage: str = stage, episodes: int = episodes) -> None:
            if progress is not None:
                progress(stage, done, episodes)

        x, y, success = demonstrate(env, config.imitate, episodes,
                                    act=None if r == 0 else act, progress=tick)  # fmt: skip
        yield r, episodes, x, y, success


def warm_start(model: Any, config: Any, progress: Callable[[str, int, int], None] | None = None
               ) -> dict[str, Any]:  # fmt: skip
    """Clone ``config.imitate`` into PPO ``model``'s actor (:class:`copi.rl.TrainConfig`'s
    imitation fields): its demonstrations, then ``dagger_rounds`` rounds of the clone
    driving; ``progress(stage, done, total)`` after each episode. Returns what it did
    (episodes, states, each round's success and final loss)."""
    import torch

    env = _demonstration_env(config)
    policy = model.policy

    def act(x: NDArray[np.float32]) -> NDArray[np.float64]:
        with torch.no_grad():
            mean = _actor_mean(policy, torch.as_tensor(x[None]))
        return mean[0].numpy().astype(np.float64)

    rounds: list[dict[str, float]] = []
    xs: list[NDArray[np.float32]] = []
    ys: list[NDArray[np.float32]] = []
    for r, episodes, x, y, success in _dagger(env, config, act, progress):
        xs.append(x)
        ys.append(y)
        losses = clone(policy, np.concatenate(xs), np.concatenate(ys),
                       epochs=config.imitation_epochs, seed=config.seed * 100 + r)  # fmt: skip
        rounds.append({"episodes": episodes, "states": len(x), "driver_success": success,
                       "loss": losses[-1]})  # fmt: skip
    return {"method": config.imitate, "rounds": rounds,
            "states": int(sum(len(x) for x in xs))}  # fmt: skip


STOP = 1e-6
"""A demonstrated move shorter than this is standing still (the clone's last class)."""


def compass_classes(y: NDArray[np.floating[Any]], n_rays: int) -> NDArray[np.int64]:
    """The class of each move ``y`` (T, 2) of the policy's frame: the ray nearest its
    direction (0 .. n_rays - 1), or ``n_rays`` for a move shorter than :data:`STOP`.

    Examples
    --------
    >>> compass_classes(np.array([[1.0, 0.0], [0.0, 0.4], [0.0, 0.0], [0.0, -1.0]]), 4).tolist()
    [0, 1, 4, 3]
    """
    y = np.asarray(y, dtype=np.float64).reshape(-1, 2)
    k = np.rint(np.arctan2(y[:, 1], y[:, 0]) * n_rays / (2 * math.pi)).astype(np.int64) % n_rays
    return np.where(np.hypot(y[:, 0], y[:, 1]) < STOP, n_rays, k)


def _fit_classes(net: Any, x: NDArray[np.float32], c: NDArray[np.int64], *, epochs: int,
                 seed: int, batch_size: int = 256, learning_rate: float = 1e-3
                 ) -> list[float]:  # fmt: skip
    """Fit the scores of ``net`` (a torch module) to the classes ``c`` of the observations
    ``x`` by cross-entropy, Adam, ``epochs`` passes in an order from ``seed``; each pass's
    mean loss."""
    import torch

    return _fit(net.parameters(), lambda xb, cb: torch.nn.functional.cross_entropy(net(xb), cb),
                x, c, epochs=epochs, seed=seed, batch_size=batch_size,
                learning_rate=learning_rate)  # fmt: skip


def _export(net: Any, config: Any, n_rays: int, max_range: float,
            info: dict[str, Any]) -> PolicyWeights:  # fmt: skip
    """The torch classifier ``net`` (linear layers, tanh between) as a ``compass`` policy."""
    import torch

    layers = [(m.weight.detach().numpy().astype(np.float64),
               m.bias.detach().numpy().astype(np.float64))
              for m in net if isinstance(m, torch.nn.Linear)]  # fmt: skip
    return PolicyWeights(tuple(layers), n_rays, max_range, info, config.observation,
                         config.levels[0], config.frames, "compass")  # fmt: skip


def train_clone(
    config: Any,
    validate: Callable[[PolicyWeights], float],
    *,
    imitating: Callable[[str, int, int], None] | None = None,
    info: dict[str, Any] | None = None,
    keep: str = "best",
) -> tuple[PolicyWeights, list[dict[str, float]], dict[str, Any]]:
    """A classifier of ``config.imitate``'s moves (:class:`copi.rl.TrainConfig` with
    ``algorithm="clone"``): a tanh network of ``config.net`` hidden layers scoring the
    N + 1 moves of a ``compass`` policy, fitted after the demonstrator's episodes and after
    each of ``dagger_rounds`` rounds of the clone driving (everything gathered so far,
    ``imitation_epochs`` passes, cross-entropy), each round's clone validated
    (``validate``: its success on the validation seed's episodes). Returns the clone of
    the best round (the latest of equals: model selection on seed 1, which no report
    uses; the last with ``keep="last"``), the curve (one point a round: the states
    gathered, the seconds, the validation success) and what it did."""
    import time

    import torch

    torch.manual_seed(config.seed)
    env = _demonstration_env(config)
    sim = env.sim
    n, reach = sim.sensor.n_rays, sim.sensor.max_range
    widths = [int(np.prod(env.observation_space.shape or (0,))), *config.net]
    mods: list[Any] = []
    for a, b in zip(widths[:-1], widths[1:], strict=True):
        mods += [torch.nn.Linear(a, b), torch.nn.Tanh()]
    net = torch.nn.Sequential(*mods, torch.nn.Linear(widths[-1], n + 1))

    def act(x: NDArray[np.float32]) -> NDArray[np.float64]:
        with torch.no_grad():
            scores = net(torch.as_tensor(x[None]))[0].numpy()
        return compass_move(scores, x, n, reach)

    t0 = time.perf_counter()
    xs: list[NDArray[np.float32]] = []
    cs: list[NDArray[np.int64]] = []
    curve: list[dict[str, float]] = []
    rounds: list[dict[str, float]] = []
    best: tuple[float, PolicyWeights] | None = None
    for r, episodes, x, y, success in _dagger(env, config, act, imitating):
        xs.append(x)
        cs.append(compass_classes(y, n))
        losses = _fit_classes(net, np.concatenate(xs), np.concatenate(cs),
                              epochs=config.imitation_epochs,
                              seed=config.seed * 100 + r)  # fmt: skip
        policy = _export(net, config, n, reach, dict(info or {}))
        valid = validate(policy)
        states = int(sum(len(v) for v in xs))
        curve.append({"steps": states, "seconds": round(time.perf_counter() - t0, 1),
                      "success": valid})  # fmt: skip
        rounds.append({"episodes": episodes, "states": len(x), "driver_success": success,
                       "loss": losses[-1], "validation_success": valid})  # fmt: skip
        policy.info.update(validation_success=valid, kept_round=r, kept=keep)
        if best is None or valid >= best[0] or keep == "last":
            best = (valid, policy)
    assert best is not None
    return best[1], curve, {"method": config.imitate, "rounds": rounds,
                            "states": int(sum(len(v) for v in xs))}  # fmt: skip
