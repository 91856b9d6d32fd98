"""Deep RL as copi's learning peer: the observation/action contract, the export of a
trained actor to numpy (equal to torch's), a short training that beats a random policy,
and bad policy files refused in one line."""

from __future__ import annotations

import dataclasses
import json
import math
from pathlib import Path

import numpy as np
import pytest

from copi.baselines import PolicyFormatError, PolicyWeights, PPOAgent, features, load_policy
from copi.baselines._ppo import direction_frame, save_policy, to_world
from copi.errors import InvalidArgumentError
from tests.cli.test_faults import _one_line_error, run

torch = pytest.importorskip("torch", reason="the optional extra rl (make install adds it)")
sb3 = pytest.importorskip("stable_baselines3", reason="the optional extra rl")


def _random_policy(seed: int = 0, net: tuple[int, ...] = (16, 16)) -> PolicyWeights:
    rng = np.random.default_rng(seed)
    sizes = [67, *net, 2]
    layers = tuple((rng.normal(0, 0.5, (b, a)), rng.normal(0, 0.1, b))
                   for a, b in zip(sizes, sizes[1:], strict=False))  # fmt: skip
    return PolicyWeights(layers)


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
            train(dataclasses.replace(cfg, learning_rate=3e-4), tmp_path / "x.npz",
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


def _tamper(src: Path, dst: Path, **changes: object) -> Path:
    from copi._files import write_npz

    with np.load(src) as z:
        arrays = {k: z[k] for k in z.files}
    meta = json.loads(str(arrays["metadata"][()]))
    for k, v in changes.items():
        if k in arrays:
            arrays[k] = v  # type: ignore[assignment]
        else:
            meta[k] = v
    arrays["metadata"] = np.array(json.dumps(meta))
    write_npz(dst, arrays)
    return dst


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"w0": np.zeros((16, 99))}, "layer 0 takes 99 inputs; expected the observation's 67"),
        ({"w0": np.full((16, 67), np.nan)}, "not finite or beyond"),
        ({"b1": np.full(16, 1e9)}, "not finite or beyond"),
        ({"w2": np.zeros((3, 16)), "b2": np.zeros(3)}, "the last layer gives 3 values"),
        ({"observation": "pixels-v2"}, "a policy of observation 'pixels-v2'"),
        ({"layers": 9}, "'layers' must be an int in 2 .. 8"),
        ({"activation": "relu"}, "activation 'relu'"),
        ({"format": "copi-capabilities"}, "not a copi policy file"),
        ({"version": 99}, "written by a newer copi"),
    ],
)
def test_bad_policy_files_are_refused_in_one_line(
    change: dict, message: str, tmp_path: Path, capsys
) -> None:
    good = save_policy(_random_policy(), tmp_path / "good.npz")
    bad = _tamper(good, tmp_path / "bad.npz", **change)
    with pytest.raises(PolicyFormatError, match=message.replace("(", r"\(").replace(")", r"\)")):
        load_policy(bad)
    out = tmp_path / "r.sqlite"
    args = ["evaluate", "--method", "ppo", "-o", str(out), "--worlds", "1"]
    from copi.methods import register_method, unregister_method

    register_method("ppo-test", PPOAgent, params={"weights": str(bad)}, replace=True)
    try:
        line = _one_line_error(*run([*args[:2], "ppo-test", *args[3:]], capsys)[::2])
        assert message.split("(")[0][:30] in line, line
    finally:
        unregister_method("ppo-test")
    assert not out.exists()


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
    ],
)
def test_bad_training_options_are_one_line(args: list[str], message: str, tmp_path: Path,
                                           capsys) -> None:  # fmt: skip
    out = tmp_path / "p.npz"
    line = _one_line_error(*run(["rl", "train", "-o", str(out), *args], capsys)[::2])
    assert message in line, line
    assert list(tmp_path.iterdir()) == []


def test_ppo_without_weights_is_left_out_or_refused(tmp_path: Path, capsys, monkeypatch) -> None:
    import copi.baselines._ppo as ppo

    monkeypatch.setattr(ppo, "POLICIES", tmp_path / "none")
    out = tmp_path / "r.sqlite"
    line = _one_line_error(*run(["evaluate", "--method", "ppo", "-o", str(out), "--worlds", "1"],
                                capsys)[::2])  # fmt: skip
    assert "ppo needs its trained weights ppo-mix.npz, which copi does not ship here" in line
    assert not out.exists()


def test_features_clip_and_normalise() -> None:
    x = features(np.r_[np.full(31, 10.0), 0.0], np.r_[np.full(31, 0.0), 10.0], [1.0, 0.0],
                 50.0, 10.0)  # fmt: skip
    assert x[0] == 1.0 and x[31] == 0.0 and x[32] == 1.0 and x[63] == -1.0
    assert x[64:].tolist() == [1.0, 0.0, 1.0]
    # pointing down (-y: ray 24 of 32): ray 24 of the sensor is the block's first
    r = np.arange(32.0) / 4
    y = features(r, None, [0.0, -2.0], 5.0, 10.0)
    assert direction_frame([0.0, -2.0], 32) == 24 and y[0] == r[24] / 10 and y[8] == r[0] / 10
    assert np.allclose(y[64:], [1.0, 0.0, 0.5])


@pytest.mark.parametrize("angle", [0.0, 0.3, 1.7, -2.9, 3.1])
def test_the_frame_is_a_symmetry(angle: float) -> None:
    """Turning the world by whole rays turns the observation not at all and the action
    with it: the policy's frame is the direction's."""
    rng = np.random.default_rng(0)
    r, prev = rng.uniform(0, 10, 32), rng.uniform(0, 10, 32)
    d = np.array([math.cos(angle), math.sin(angle)])
    for j in (1, 5, 20):
        turned = np.array([[math.cos(2 * math.pi * j / 32), -math.sin(2 * math.pi * j / 32)],
                           [math.sin(2 * math.pi * j / 32), math.cos(2 * math.pi * j / 32)]])
        a = features(r, prev, d, 3.0, 10.0)
        b = features(np.roll(r, j), np.roll(prev, j), turned @ d, 3.0, 10.0)
        np.testing.assert_allclose(a, b, atol=1e-9)
        v = np.array([0.3, -0.4])
        np.testing.assert_allclose(
            turned @ to_world(v, direction_frame(d, 32), 32),
            to_world(v, direction_frame(turned @ d, 32), 32), atol=1e-9)


def test_every_shipped_policy_loads_and_says_how_it_was_trained() -> None:
    """The weights copi ships (seed 0 for the benchmark, the other seeds for the spread)
    pass the loader's checks, and each names the command that trained it, in the
    repository's terms (no directory of the machine it ran on)."""
    from copi.baselines._ppo import POLICIES, load_policy

    files = sorted(POLICIES.glob("*.npz")) + sorted((POLICIES / "seeds").glob("*.npz"))
    assert len(files) >= 7
    for path in files:
        command = load_policy(path).info.get("command", "")
        assert command.startswith("copi rl train -o results/rl/ppo-"), (path.name, command)
        assert " --steps 2000000 " in command and " --seed " in command
        if path.parent.name == "seeds":
            seed = path.stem.rsplit("-s", 1)[1]
            assert command.endswith(f"--seed {seed}") and seed != "0"
