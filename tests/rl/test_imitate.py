"""PPO's imitation warm start (``copi rl train --imitate``): the demonstrator is told what
the runner tells it, its moves are labelled in the policy's frame, a clone fits them,
DAgger's rounds are driven by the clone, a resumed run does not clone again, and bad
demonstrators are refused in one line. Needs the extra rl."""

from __future__ import annotations

import copy
import dataclasses
import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from copi.errors import InvalidArgumentError
from tests.cli.test_faults import _one_line_error, run

torch = pytest.importorskip("torch", reason="the optional extra rl (make install adds it)")
sb3 = pytest.importorskip("stable_baselines3", reason="the optional extra rl")


def _env(level: str = "map", families: tuple[str, ...] = ("star",)) -> Any:
    from copi.rl import LocalPolicyEnv

    class Recorded(LocalPolicyEnv):
        """Keeps each episode's simulator as drawn and where it ends."""

        def reset(self, **kw: Any) -> Any:
            out = super().reset(**kw)
            self.drawn = copy.deepcopy(self.sim)
            return out

        def step(self, action: Any) -> Any:
            out = super().step(action)
            self.last = (self.sim.position.copy(), self.t, out[4].get("is_success"))
            return out

    return Recorded(families, levels=(level,), observation="copi-local-v3", frames=3)


@pytest.mark.parametrize("level", ["map", "sensor"])
def test_the_demonstrator_drives_as_in_an_episode_and_is_labelled_in_the_policy_frame(
    level: str,
) -> None:
    """Driven by its own labels (turned back to the world's frame by the environment), the
    demonstrator's episode is the one the runner gives it: the same steps, outcome and
    end, to rounding; so each label is its move, in the policy's frame."""
    from copi.methods import make_agent
    from copi.rl._imitate import demonstrate
    from copi.runs import run_episode

    env = _env(level)
    env.reset(seed=5)
    for _ in range(3):
        x, y, success = demonstrate(env, "compass-guard", 1)
        end, steps, won = env.last
        assert x.shape == (steps, env.observation_space.shape[0]) and y.shape == (steps, 2)
        assert np.all(np.hypot(y[:, 0], y[:, 1]) <= 1.0 + 1e-6)
        out = run_episode(make_agent("compass-guard", None), copy.deepcopy(env.drawn),
                          sensing=level, max_steps=env.max_steps)  # fmt: skip
        assert out.steps == steps and (out.outcome == "success") == bool(won) == (success == 1)
        sim = copy.deepcopy(env.drawn)
        run_episode(make_agent("compass-guard", None), sim, sensing=level,
                    max_steps=env.max_steps)  # fmt: skip
        np.testing.assert_allclose(sim.position, end, atol=1e-6)


def test_a_clone_fits_its_demonstrations_and_drives_dagger_s_rounds() -> None:
    from stable_baselines3 import PPO
    from stable_baselines3.common.vec_env import DummyVecEnv

    from copi.rl._imitate import clone, demonstrate

    env = _env()
    env.reset(seed=1)
    x, y, _ = demonstrate(env, "compass-guard", 30)
    model = PPO("MlpPolicy", DummyVecEnv([_env]), seed=0, device="cpu",
                policy_kwargs={"net_arch": [64, 64]})  # fmt: skip
    losses = clone(model.policy, x, y, epochs=15)
    assert losses[-1] < 0.3 * losses[0], losses
    # the clone drives; the demonstrator still labels every state it meets
    seen: list[int] = []
    x2, y2, _ = demonstrate(env, "compass-guard", 5, act=lambda o: (seen.append(1), y[0])[1],
                            progress=lambda done: seen.append(-done))  # fmt: skip
    assert seen.count(1) == len(x2) == len(y2) and [-s for s in seen if s < 0] == [1, 2, 3, 4, 5]
    with pytest.raises(InvalidArgumentError, match="nothing to imitate"):
        clone(model.policy, x[:0], y[:0], epochs=1)


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"imitate": "moon"}, "the demonstrator: method must be one of .*; got 'moon'"),
        ({"imitate": "copi-learnt"}, "must need no capabilities file; 'copi-learnt' needs"),
        ({"imitate": "model-oracle"}, r"must run at level map \(the policy's\); 'model-oracle'"),
    ],
)
def test_a_demonstrator_it_cannot_imitate_is_one_line(change: dict[str, Any], message: str,
                                                       tmp_path: Path) -> None:  # fmt: skip
    from copi.rl import TrainConfig, train

    cfg = TrainConfig(families=("star",), steps=1000, envs=1, n_steps=64, batch_size=64,
                      imitation_episodes=1, **change)  # fmt: skip
    with pytest.raises(InvalidArgumentError, match=message) as err:
        train(cfg, tmp_path / "p.npz")
    assert "\n" not in str(err.value) and list(tmp_path.iterdir()) == []


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"imitate": "straight", "algorithm": "sac"}, "imitate needs PPO or a clone on navigation"),
        ({"imitate": "straight", "task": "chauffeur"}, "imitate needs PPO or a clone on navigation"),
        ({"imitate": "straight", "imitation_epochs": 0}, "imitation_epochs must be an int"),
        ({"imitate": "straight", "dagger_rounds": -1}, "dagger_rounds must be an int in 0"),
        ({"imitate": 3}, "imitate must be a method's name; got 3"),
    ],
)
def test_imitation_settings_are_checked(change: dict[str, Any], message: str) -> None:
    from copi.rl import TrainConfig

    with pytest.raises(InvalidArgumentError, match=message):
        TrainConfig(**change)


def test_a_run_without_imitation_keeps_its_identity() -> None:
    """Policies and checkpoints trained before the warm start keep their identity."""
    from copi.rl import TrainConfig

    assert not {"imitate", "dagger_rounds"} & set(TrainConfig().identity())
    assert TrainConfig(imitate="straight").identity()["imitate"] == "straight"


def test_training_clones_first_validates_the_clone_and_resumes_without_cloning(
    tmp_path: Path,
) -> None:
    from copi.rl import TrainConfig, train

    cfg = TrainConfig(families=("star",), steps=2048, envs=2, n_steps=256, batch_size=256,
                      net=(32, 32), imitate="compass-guard", imitation_episodes=12,
                      dagger_rounds=1, imitation_epochs=5)  # fmt: skip
    stages: list[str] = []
    ckpt = tmp_path / "ckpt"
    summary = train(dataclasses.replace(cfg, steps=1024), tmp_path / "a.npz", checkpoints=ckpt,
                    validate_every=1000, validation_episodes=4,
                    imitating=lambda stage, done, total: stages.append(stage))  # fmt: skip
    assert summary["curve"][0]["steps"] == 0  # the clone's own validation
    rounds = summary["imitation"]["rounds"]
    assert [r["episodes"] for r in rounds] == [12, 6] and stages[0].startswith("imitation")
    again = train(cfg, tmp_path / "b.npz", checkpoints=ckpt, validate_every=1000,
                  validation_episodes=4,
                  imitating=lambda *a: pytest.fail("a resumed run cloned again"))  # fmt: skip
    assert "imitation" not in again and again["curve"][0]["steps"] == 0
    assert json.loads((tmp_path / "b.json").read_text())["steps"] >= 2048


def test_an_unknown_demonstrator_on_the_command_line_is_one_line(tmp_path: Path,
                                                                 capsys) -> None:  # fmt: skip
    out = tmp_path / "p.npz"
    code, _, err = run(["rl", "train", "-o", str(out), "--imitate", "moon"], capsys)
    assert code == 2 and "the demonstrator: method must be one of" in _one_line_error(code, err)
    assert list(tmp_path.iterdir()) == []


def test_the_pool_of_training_episodes_can_be_chosen() -> None:
    """A pool of n episodes draws n distinct episodes at most; the default pool keeps a
    run's identity (and the episodes it drew) as before the pool could be chosen."""
    from copi.rl import LocalPolicyEnv, TrainConfig

    env = LocalPolicyEnv(("star",), levels=("map",), episodes=3)
    env.reset(seed=0)
    starts = set()
    for _ in range(30):
        env.reset()
        starts.add(tuple(np.round(env.sim.position, 9)))
    assert 1 < len(starts) <= 3
    assert "episodes" not in TrainConfig().identity()
    assert TrainConfig(episodes=50_000).identity()["episodes"] == 50_000
    for bad in (0, 2_000_000, 1.5, True):
        with pytest.raises(InvalidArgumentError, match="episodes must be an int in 1 .. 1,000,000"):
            LocalPolicyEnv(("star",), episodes=bad)
        with pytest.raises(InvalidArgumentError, match="episodes must be an int in 1 .. 1,000,000"):
            TrainConfig(episodes=bad)
