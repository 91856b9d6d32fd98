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
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import NDArray

from copi.baselines import direction_frame, to_world
from copi.core import Observation
from copi.envs.local_policy import LocalPolicyEnv
from copi.errors import InvalidArgumentError
from copi.methods import make_agent, method_spec
from copi.runs import make_task, velocity_of

__all__ = ["check_demonstrator", "clone", "demonstrate", "warm_start"]


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

    if len(x) == 0:
        raise InvalidArgumentError("nothing to imitate: no demonstrations")
    params = [*policy.mlp_extractor.policy_net.parameters(), *policy.action_net.parameters()]
    opt = torch.optim.Adam(params, lr=learning_rate)
    xt = torch.as_tensor(x)
    yt = torch.as_tensor(np.clip(y, -1.0, 1.0))
    gen = torch.Generator().manual_seed(int(seed))
    losses = []
    for _ in range(int(epochs)):
        order = torch.randperm(len(xt), generator=gen)
        total = 0.0
        for i in range(0, len(xt), batch_size):
            idx = order[i : i + batch_size]
            loss = torch.nn.functional.mse_loss(_actor_mean(policy, xt[idx]), yt[idx])
            opt.zero_grad()
            loss.backward()
            opt.step()
            total += loss.item() * len(idx)
        losses.append(total / len(xt))
    return losses


def warm_start(model: Any, config: Any, progress: Callable[[str, int, int], None] | None = None
               ) -> dict[str, Any]:  # fmt: skip
    """Clone ``config.imitate`` into PPO ``model``'s actor (:class:`copi.rl.TrainConfig`'s
    imitation fields): its demonstrations, then ``dagger_rounds`` rounds of the clone
    driving; ``progress(stage, done, total)`` after each episode. Returns what it did
    (episodes, states, each round's success and final loss)."""
    import torch

    env = LocalPolicyEnv(config.families, levels=config.levels, reward=config.reward,
                         max_steps=config.max_steps, observation=config.observation,
                         frames=config.frames, episodes=config.episodes)  # fmt: skip
    env.reset(seed=config.seed * 1000 + 999)  # apart from the training environments'
    policy = model.policy

    def act(x: NDArray[np.float32]) -> NDArray[np.float64]:
        with torch.no_grad():
            mean = _actor_mean(policy, torch.as_tensor(x[None]))
        return mean[0].numpy().astype(np.float64)

    rounds: list[dict[str, float]] = []
    xs: list[NDArray[np.float32]] = []
    ys: list[NDArray[np.float32]] = []
    for r in range(config.dagger_rounds + 1):
        episodes = config.imitation_episodes if r == 0 else max(1, config.imitation_episodes // 2)
        stage = f"imitation: {config.imitate} drives" if r == 0 else f"DAgger round {r}"

        def tick(done: int, stage: str = stage, episodes: int = episodes) -> None:
            if progress is not None:
                progress(stage, done, episodes)

        x, y, success = demonstrate(env, config.imitate, episodes,
                                    act=None if r == 0 else act, progress=tick)  # fmt: skip
        xs.append(x)
        ys.append(y)
        losses = clone(policy, np.concatenate(xs), np.concatenate(ys),
                       epochs=config.imitation_epochs, seed=config.seed * 100 + r)  # fmt: skip
        rounds.append({"episodes": episodes, "states": len(x), "driver_success": success,
                       "loss": losses[-1]})  # fmt: skip
    return {"method": config.imitate, "rounds": rounds,
            "states": int(sum(len(x) for x in xs))}  # fmt: skip
