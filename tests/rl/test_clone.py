"""A clone (``copi rl train --algo clone``): a ``compass`` policy scores a step along each
ray of its frame and standing still, takes the best, and near the goal steps as
compass-guard does; it runs in numpy (one decision or a batch alike), its file round trips
and refuses a last layer of another size; compass-guard's moves are exactly the clone's
classes; a short clone fits its demonstrations and runs as a method; bad runs are one
line. Only the training needs the extra rl."""

from __future__ import annotations

import dataclasses
import json
import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from copi.baselines import (
    OBSERVATION_V3,
    PolicyFormatError,
    PolicyWeights,
    PPOAgent,
    compass_move,
    load_policy,
    observation_size,
    save_policy,
)
from copi.errors import InvalidArgumentError
from copi.rl._imitate import compass_classes
from tests.cli.test_faults import _one_line_error, run

N = 32


def _compass(seed: int, hidden: int = 16, level: str = "map") -> PolicyWeights:
    rng = np.random.default_rng(seed)
    size = observation_size(N, OBSERVATION_V3, level, 3)
    layers = ((rng.normal(0, 0.5, (hidden, size)), rng.normal(0, 0.1, hidden)),
              (rng.normal(0, 1.0, (N + 1, hidden)), rng.normal(0, 0.1, N + 1)))  # fmt: skip
    return PolicyWeights(layers, N, 10.0, {}, OBSERVATION_V3, level, 3, "compass")


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 10_000), reach=st.floats(0.0, 1.0, allow_subnormal=False))
def test_a_compass_policy_takes_its_best_move_one_at_a_time_or_in_a_batch(seed: int,
                                                                        reach: float) -> None:  # fmt: skip
    """The numpy decision is the argmax of the scores (the same one by one and batched):
    a step along the best ray of the frame, of length 1 unless the aim is nearer than one
    step (then compass-guard's: level with it, at least half the way), or none."""
    policy = _compass(seed)
    rng = np.random.default_rng(seed)
    x = rng.random((6, policy.size))
    x[:, -1] = reach * rng.random(6)  # the reach, over the range: some nearer than a step
    moves = np.array([policy.act(r) for r in x])
    assert np.array_equal(moves, policy.act_batch(x))
    for r, v in zip(x, moves, strict=True):
        h = r.copy()
        for w, b in policy.layers[:-1]:
            h = np.tanh(w @ h + b)
        scores = policy.layers[-1][0] @ h + policy.layers[-1][1]
        m = int(np.argmax(scores))
        if m == N:
            assert v.tolist() == [0.0, 0.0]
            continue
        a = 2 * math.pi * m / N
        d = r[-1] * 10.0
        along = math.cos(a) * r[-3] + math.sin(a) * r[-2]
        want = 1.0 if d >= 1.0 else max(along * d, 0.5 * d)
        assert math.hypot(*v) == pytest.approx(want, abs=1e-12)
        if want > 1e-9:  # its direction (a step of nothing has none to speak of)
            assert np.allclose(v / want, [math.cos(a), math.sin(a)], atol=1e-9)


def test_the_step_near_the_goal_is_compass_guard_s() -> None:
    from copi.online.kernels import _step_length

    x = np.zeros(10)
    x[-3:] = (math.cos(0.3), math.sin(0.3), 0.07)  # the aim 0.7 away, 0.3 rad off ray 0
    for m, values in ((0, [1.0, 0, 0, 0, 0]), (1, [0, 1.0, 0, 0, 0])):
        v = compass_move(values, x, 4, 10.0)
        a = 2 * math.pi * m / 4
        along = math.cos(a - 0.3)
        assert math.hypot(*v) == pytest.approx(_step_length(along * 0.7, 0.7))


def test_a_compass_policy_file_round_trips_and_refuses_another_last_layer(tmp_path: Path) -> None:
    policy = _compass(3)
    path = save_policy(policy, tmp_path / "c.npz")
    again = load_policy(path)
    assert again.output == "compass" and again.outputs == N + 1
    x = np.random.default_rng(0).random(policy.size)
    assert np.array_equal(again.act(x), policy.act(x))
    (w, b), (w2, b2) = policy.layers
    with pytest.raises(InvalidArgumentError, match="scores 33 moves"):
        PolicyWeights(((w, b), (w2[:2], b2[:2])), N, 10.0, {}, OBSERVATION_V3, "map", 3,
                      "compass")  # fmt: skip
    two = dataclasses.replace(policy, layers=((w, b), (w2[:2], b2[:2])), output="clip")
    bad = save_policy(two, tmp_path / "two.npz")
    with np.load(bad) as z:  # a velocity's layer under a compass policy's name
        arrays = {k: z[k] for k in z.files}
    meta = json.loads(str(arrays["metadata"]))
    arrays["metadata"] = np.array(json.dumps(meta | {"output": "compass"}))
    np.savez(tmp_path / "forged.npz", **arrays)
    with pytest.raises(PolicyFormatError, match="scores 33 moves"):
        load_policy(tmp_path / "forged.npz")


def test_compass_guard_s_moves_are_the_clone_s_classes() -> None:
    """Every move compass-guard makes in star and crowd episodes, in the policy's frame,
    lies along the ray of its class (its 16 directions are every other ray of 32, and the
    frame turns by whole rays): the classes lose only the step's length near the goal,
    which the clone's rule restores."""
    from copi.envs.local_policy import LocalPolicyEnv
    from copi.rl._imitate import demonstrate

    for family in ("star", "crowd"):
        env = LocalPolicyEnv((family,), levels=("map",), observation=OBSERVATION_V3, frames=3)
        env.reset(seed=2)
        _, y, _ = demonstrate(env, "compass-guard", 4)
        c = compass_classes(y, N)
        moving = c < N
        a = 2 * np.pi * c[moving] / N
        unit = y[moving] / np.hypot(y[moving, 0], y[moving, 1])[:, None]
        assert np.allclose(unit, np.column_stack([np.cos(a), np.sin(a)]), atol=1e-6)
        assert moving.mean() > 0.9  # it stands still only where nothing is admitted


def test_a_short_clone_fits_its_demonstrator_and_runs_as_a_method(tmp_path: Path) -> None:
    pytest.importorskip("torch", reason="the optional extra rl (make install adds it)")
    from copi.rl import TrainConfig, train
    from copi.runs import Episode

    cfg = TrainConfig(families=("star",), algorithm="clone", imitate="compass-guard",
                      imitation_episodes=30, dagger_rounds=1, imitation_epochs=20,
                      net=(64, 64), episodes=200)  # fmt: skip
    stages: list[str] = []
    summary = train(cfg, tmp_path / "c.npz", validation_episodes=6,
                    imitating=lambda stage, done, total: stages.append(stage))  # fmt: skip
    rounds = summary["imitation"]["rounds"]
    assert [r["episodes"] for r in rounds] == [30, 15] and len(summary["curve"]) == 2
    assert rounds[-1]["loss"] < 0.5 * math.log(N + 1)  # far below guessing among 33
    assert stages[0].startswith("imitation") and stages[-1] == "DAgger round 1"
    policy = load_policy(tmp_path / "c.npz")
    assert policy.output == "compass" and policy.info["algorithm"].startswith("behaviour")
    assert "steps" not in policy.info and policy.info["imitate"] == "compass-guard"
    assert (tmp_path / "c.json").is_file() and (tmp_path / "c.png").is_file()
    out = Episode.draw("star", 0, 1).run(PPOAgent(policy=policy), sensing="map")
    assert out.outcome in ("success", "collision", "timeout")
    with pytest.raises(InvalidArgumentError, match="takes no checkpoints"):
        train(cfg, tmp_path / "d.npz", checkpoints=tmp_path / "ck")


def test_a_clone_needs_its_demonstrator(tmp_path: Path, capsys) -> None:  # fmt: skip
    from copi.rl import TrainConfig

    with pytest.raises(InvalidArgumentError, match="a clone needs the method it imitates"):
        TrainConfig(algorithm="clone")
    assert "steps" not in TrainConfig(algorithm="clone", imitate="compass-guard").identity()
    out = tmp_path / "p.npz"
    code, _, err = run(["rl", "train", "-o", str(out), "--algo", "clone"], capsys)
    assert code == 2 and "a clone needs the method it imitates" in _one_line_error(code, err)
    assert list(tmp_path.iterdir()) == []
