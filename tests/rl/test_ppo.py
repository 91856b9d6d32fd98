"""Deep RL as copi's learning peer: the observation/action contract, the export of a
trained actor to numpy (equal to torch's), a short training that beats a random policy,
and bad policy files refused in one line."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from copi.baselines import PolicyFormatError, PolicyWeights, PPOAgent, features, load_policy
from copi.baselines._ppo import save_policy
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
    assert np.allclose(obs[:32], env.sim.ranges / 10.0, atol=1e-6)
    assert np.allclose(obs[32:64], 0.0)  # no change on the first step
    assert np.hypot(obs[64], obs[65]) == pytest.approx(1.0, abs=1e-6)
    before, where = env.sim.ranges.copy(), env.sim.position.copy()
    obs, reward, *_ = env.step(np.array([3.0, 4.0], dtype=np.float32))  # norm 5: clipped to 1
    assert np.hypot(*(env.sim.position - where)) <= 1.0 + 1e-9
    change = np.clip(env.sim.ranges - before, -1.5, 1.5) / 1.5
    assert np.allclose(obs[32:64], change, atol=1e-6)
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
    from copi.experiments import run_episode
    from copi.rl import TrainConfig, train
    from copi.world import ObstacleSpec, World, register_family, unregister_family

    def room(rng, *, name=None):  # noqa: ANN001, ANN202
        side = float(rng.uniform(14, 20))
        return World(np.array([[0, 0], [side, 0], [side, side], [0, side]]), name=name or "room",
                     obstacles=ObstacleSpec(count=(0, 0)))  # fmt: skip

    register_family("empty-room", room)
    try:
        cfg = TrainConfig(families=("empty-room",), levels=("sensor",), steps=24_000, envs=4,
                          n_steps=256, batch_size=256, net=(32, 32))  # fmt: skip
        summary = train(cfg, tmp_path / "p.npz", validate_every=12_000, validation_episodes=10)
        assert summary["steps"] >= 24_000 and (tmp_path / "p.png").is_file()
        curve = json.loads((tmp_path / "p.json").read_text())["curve"]
        assert curve[-1]["success"] == summary["curve"][-1]["success"]
        from copi.experiments.navigation import draw_episode

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
    from copi.experiments import register_method, unregister_method

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
    x = features(np.r_[np.full(31, 10.0), 0.0], np.r_[np.full(31, 0.0), 10.0], [0.0, -2.0],
                 50.0, 10.0)  # fmt: skip
    assert x[0] == 1.0 and x[31] == 0.0 and x[32] == 1.0 and x[63] == -1.0
    assert x[64:].tolist() == [0.0, -1.0, 1.0]
