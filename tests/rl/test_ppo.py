"""Deep RL as copi's learning peer: the observation/action contract, the export of a
trained actor to numpy (equal to torch's), a short training that beats a random policy,
and bad training options refused in one line. Everything here needs the extra rl
(torch, Stable-Baselines3); what runs a trained policy without it is tested in
tests/rl/test_policy.py, never skipped."""

from __future__ import annotations

import dataclasses
import json
import math
from pathlib import Path

import numpy as np
import pytest

from copi.baselines import PPOAgent, load_policy
from copi.baselines._ppo import direction_frame, save_policy, to_world
from copi.errors import InvalidArgumentError
from tests.cli.test_faults import _one_line_error, run
from tests.rl.test_policy import _random_policy

torch = pytest.importorskip("torch", reason="the optional extra rl (make install adds it)")
sb3 = pytest.importorskip("stable_baselines3", reason="the optional extra rl")


def test_the_observation_is_what_the_agent_sees() -> None:
    from gymnasium.utils.env_checker import check_env

    from copi.rl import LocalPolicyEnv

    env = LocalPolicyEnv(("star",), levels=("map",))
    check_env(env, skip_render_check=True)
    obs, _ = env.reset(seed=3)
    assert obs.shape == (67,) and env.observation_space.contains(obs)
    # the reading turned by the rays of the direction's angle: the direction within half
    # a ray of the block's first ray
    k = direction_frame(env.direction, 32)
    assert np.allclose(obs[:32], np.roll(env.sim.ranges, -k) / 10.0, atol=1e-6)
    assert np.allclose(obs[32:64], 0.0)  # no change on the first step
    assert np.hypot(obs[64], obs[65]) == pytest.approx(1.0, abs=1e-6)
    assert abs(math.atan2(obs[65], obs[64])) <= math.pi / 32 + 1e-6
    before, where, k = env.sim.ranges.copy(), env.sim.position.copy(), k
    # the action is of the policy's frame: clipped per component and to norm 1, then
    # turned back by k rays, as PPOAgent turns it
    obs, reward, *_ = env.step(np.array([3.0, 4.0], dtype=np.float32))  # norm 5: clipped to 1
    moved = env.sim.position - where
    assert np.hypot(*moved) <= 1.0 + 1e-9
    if np.hypot(*moved) > 0.99:  # not stopped by a wall
        np.testing.assert_allclose(moved, to_world(np.array([1.0, 1.0]) / math.sqrt(2), k, 32),
                                   atol=1e-9)  # fmt: skip
    change = np.clip(env.sim.ranges - before, -1.5, 1.5) / 1.5
    assert np.allclose(obs[32:64], np.roll(change, -direction_frame(env.direction, 32)),
                       atol=1e-6)  # fmt: skip
    with pytest.raises(ValueError, match="action must be 2 finite numbers"):
        env.step(np.array([np.nan, 0.0]))


def test_the_export_runs_in_numpy_as_the_torch_policy_does(tmp_path: Path) -> None:
    from stable_baselines3 import PPO

    from copi.rl import LocalPolicyEnv
    from copi.rl._train import export_policy

    model = PPO("MlpPolicy", LocalPolicyEnv(("star",)), seed=0, device="cpu", n_steps=64,
                policy_kwargs={"net_arch": {"pi": [32, 16], "vf": [32, 16]},
                               "activation_fn": torch.nn.Tanh})  # fmt: skip
    policy = export_policy(model)
    x = np.random.default_rng(0).uniform(-1, 1, (200, 67)).astype(np.float32)
    with torch.no_grad():
        mean = model.policy.get_distribution(torch.as_tensor(x)).distribution.mean.numpy()
    want = np.clip(mean, -1, 1)
    norm = np.hypot(want[:, 0], want[:, 1])
    want[norm > 1] /= norm[norm > 1, None]
    np.testing.assert_allclose(policy.act_batch(x), want, atol=1e-5)
    np.testing.assert_allclose([policy.act(xi.astype(np.float64)) for xi in x], want, atol=1e-5)
    path = save_policy(policy, tmp_path / "p.npz")
    np.testing.assert_allclose(load_policy(path).act_batch(x), want, atol=1e-5)


def test_a_sac_actor_runs_in_numpy_as_torch_s_squashed_mean(tmp_path: Path) -> None:
    from stable_baselines3 import SAC

    from copi.rl import LocalPolicyEnv
    from copi.rl._train import export_policy

    model = SAC("MlpPolicy", LocalPolicyEnv(("star",)), seed=0, device="cpu",
                learning_starts=0, buffer_size=100,
                policy_kwargs={"net_arch": {"pi": [32, 16], "qf": [32, 16]},
                               "activation_fn": torch.nn.Tanh})  # fmt: skip
    policy = export_policy(model)
    assert policy.output == "tanh"
    x = np.random.default_rng(0).uniform(-1, 1, (200, 67)).astype(np.float32)
    with torch.no_grad():
        want = model.actor(torch.as_tensor(x), deterministic=True).numpy().astype(np.float64)
    norm = np.hypot(want[:, 0], want[:, 1])
    want[norm > 1] /= norm[norm > 1, None]
    np.testing.assert_allclose(policy.act_batch(x), want, atol=1e-5)
    np.testing.assert_allclose([policy.act(xi.astype(np.float64)) for xi in x], want, atol=1e-5)
    path = save_policy(policy, tmp_path / "p.npz")
    back = load_policy(path)
    assert back.output == "tanh"
    np.testing.assert_allclose(back.act_batch(x), want, atol=1e-5)


def test_a_short_training_beats_a_random_policy(tmp_path: Path) -> None:
    from copi.rl import TrainConfig, train
    from copi.runs import run_episode
    from copi.world import ObstacleSpec, World, register_family, unregister_family

    def room(rng, *, name=None):  # noqa: ANN001, ANN202
        side = float(rng.uniform(14, 20))
        return World(np.array([[0, 0], [side, 0], [side, side], [0, side]]), name=name or "room",
                     obstacles=ObstacleSpec(count=(0, 0)))  # fmt: skip

    register_family("empty-room", room)
    try:
        cfg = TrainConfig(families=("empty-room",), levels=("sensor",), steps=24_000, envs=4,
                          n_steps=256, batch_size=256, net=(32, 32))  # fmt: skip
        ckpt = tmp_path / "ckpt"
        half = dataclasses.replace(cfg, steps=12_000)
        train(half, tmp_path / "half.npz", checkpoints=ckpt, validate_every=6_000,
              validation_episodes=10)  # fmt: skip
        # a checkpoint of another run is refused; the same run with more steps resumes
        with pytest.raises(InvalidArgumentError, match="another training run"):
            train(dataclasses.replace(cfg, learning_rate=1e-3), tmp_path / "x.npz",
                  checkpoints=ckpt)  # fmt: skip
        summary = train(cfg, tmp_path / "p.npz", checkpoints=ckpt, validate_every=6_000,
                        validation_episodes=10)  # fmt: skip
        assert summary["steps"] >= 24_000 and (tmp_path / "p.png").is_file()
        curve = json.loads((tmp_path / "p.json").read_text())["curve"]
        assert curve[-1]["success"] == summary["curve"][-1]["success"]
        # validated between rollouts (4 envs x 256 steps), at the first one past each 6,000
        assert [c["steps"] for c in curve][:2] == [6_144, 12_288] and len(curve) >= 4
        from copi.runs import draw_episode

        trained = PPOAgent(weights=str(tmp_path / "p.npz"))
        rand = PPOAgent(policy=_random_policy(1))
        won = {"trained": 0, "random": 0}
        for k in range(12):
            for name, agent in (("trained", trained), ("random", rand)):
                sim = draw_episode("empty-room", k, 0)
                won[name] += run_episode(agent, sim, sensing="sensor",
                                         max_steps=120).outcome == "success"  # fmt: skip
        assert won["trained"] > won["random"] and won["trained"] >= 9, won
    finally:
        unregister_family("empty-room")


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--families", "moon"], "family must be one of"),
        (["--steps", "0"], "Invalid value for '--steps'"),
        (["--task", "fly"], "task must be navigation or chauffeur"),
        (["--net", "64,x"], "--net must be comma-separated ints"),
        (["--levels", "oracle"], "a local policy runs at sensor or map"),
        (["--seed", str(2**32)], "seed must be an int in 0 .. 4,294,967,295"),
        (["--net", ",".join(["8"] * 8)], "net must be 1 to 7 layer widths"),
        (["--levels", "sensor,map"], "is learnt at one level"),
        (["--observation", "pixels"], "observation must be one of"),
        (["--observation", "copi-local-v2", "--frames", "3"], "frames must be an int in 2"),
        (["--frames", "99"], "Invalid value for '--frames'"),
        (["--algo", "dqn"], "algorithm must be one of ppo, sac, clone; got 'dqn'"),
        (["--episodes-per-family", "0"], "Invalid value for '--episodes-per-family'"),
        (["--algo", "sac", "--buffer-size", "0"], "Invalid value for '--buffer-size'"),
        (["--algo", "sac", "--buffer-size", "4"], "buffer_size must be at least envs (8)"),
        (["--algo", "sac", "--buffer-size", "9000000"], "buffer_size must be at most 1,713,417 for this"),
    ],
)
def test_bad_training_options_are_one_line(args: list[str], message: str, tmp_path: Path,
                                           capsys) -> None:  # fmt: skip
    out = tmp_path / "p.npz"
    line = _one_line_error(*run(["rl", "train", "-o", str(out), *args], capsys)[::2])
    assert message in line, line
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("level", ["map", "sensor"])
def test_the_v3_env_shows_what_the_v3_agent_sees(level: str) -> None:
    """Training's contract with inference, step by step: the env's copi-local-v3
    observation, fed to a policy, gives the velocity PPOAgent gives in the same state
    (so they see the same reading, unexplained hits, stacked readings and velocity)."""
    from copi.core import Observation
    from copi.rl import LocalPolicyEnv
    from copi.runs import make_task
    from tests.rl.test_policy import _random_v3

    policy = _random_v3(level, 3, seed=1)
    env = LocalPolicyEnv(("star",), levels=(level,), observation="copi-local-v3", frames=3)
    obs, _ = env.reset(seed=4)
    assert obs.shape == (policy.size,)
    agent = PPOAgent(policy=policy)
    agent.reset(make_task(env.sim, level))
    for _ in range(12):
        sim = env.sim
        seen = Observation(ranges=sim.ranges.copy(), goal=sim.goal - sim.position,
                           position=sim.position.copy() if level == "map" else None,
                           static=sim.sensor.scan(sim.world, sim.position) if level == "map"
                           else None)  # fmt: skip
        v = agent.act(seen)
        a = policy.act(obs.astype(np.float64))
        np.testing.assert_allclose(to_world(a, direction_frame(env.direction, 32), 32), v,
                                   atol=1e-5)  # float32 observations  # fmt: skip
        obs, _, done, cut, _ = env.step(a)
        if done or cut:
            break


def test_a_v3_evader_learns_at_the_level_it_is_given() -> None:
    """The game gives its evader level sensor: a copi-local-v3 evader is trained at the
    level it is told (its observation that level's), the first peer's at map whatever."""
    from copi.baselines import OBSERVATION_V3, observation_size
    from copi.envs.local_policy import LocalPolicyEnv
    from copi.rl import TrainConfig

    for level in ("sensor", "map"):
        env = LocalPolicyEnv(task="chauffeur", levels=(level,), observation=OBSERVATION_V3,
                             frames=3)  # fmt: skip
        obs, _ = env.reset(seed=0)
        assert env.level == level
        assert obs.shape == (observation_size(32, OBSERVATION_V3, level, 3),)
    assert observation_size(32, OBSERVATION_V3, "sensor", 3) < observation_size(
        32, OBSERVATION_V3, "map", 3)  # map adds the hits the static map does not explain
    assert LocalPolicyEnv(task="chauffeur", levels=("sensor", "map")).levels == ("map",)
    with pytest.raises(InvalidArgumentError, match="one level"):
        TrainConfig(task="chauffeur", levels=("sensor", "map"))
