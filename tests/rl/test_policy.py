"""The PPO policy without torch: what it sees (:func:`copi.baselines.features`, checked
against values worked out by hand in the direction's frame), the frame's symmetry, the
numpy forward pass (against one written out here), the agent that runs it, and bad
policy files refused in one line. Running a trained policy needs none of the extra rl,
so nothing here is skipped without it (tests/rl/test_ppo.py holds what needs torch)."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from copi.baselines import PolicyFormatError, PolicyWeights, PPOAgent, features, load_policy
from copi.baselines._ppo import direction_frame, save_policy, to_world
from copi.core import Observation, Task
from tests.cli.test_faults import _one_line_error, run


def _random_policy(seed: int = 0, net: tuple[int, ...] = (16, 16)) -> PolicyWeights:
    rng = np.random.default_rng(seed)
    sizes = [67, *net, 2]
    layers = tuple((rng.normal(0, 0.5, (b, a)), rng.normal(0, 0.1, b))
                   for a, b in zip(sizes, sizes[1:], strict=False))  # fmt: skip
    return PolicyWeights(layers)


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


@pytest.mark.parametrize("off", [0.07, -0.07])
def test_features_are_the_reading_seen_from_the_direction(off: float) -> None:
    """A known reading and direction, worked out by hand: the direction points 0.07 rad
    past (or short of) ray 9, where a disc 2 away came 1 nearer since the last step and
    a wall 4 away (ray 25, behind) went 3 farther. In the direction's frame the disc is
    ahead (block ray 0), the wall behind (block ray 16), the direction 0.07 rad to the
    left (right) of +x, and every sign is the world's: nearer is negative change, left
    is positive y."""
    ranges = np.full(32, 10.0)
    previous = np.full(32, 10.0)
    ranges[9], previous[9] = 2.0, 3.0  # came 1 nearer
    ranges[25], previous[25] = 4.0, 1.0  # went 3 farther: clipped to 1.5
    angle = 2 * math.pi * 9 / 32 + off
    direction = 3.0 * np.array([math.cos(angle), math.sin(angle)])
    x = features(ranges, previous, direction, 2.5, 10.0)
    assert direction_frame(direction, 32) == 9
    want = np.ones(67)
    want[0], want[16] = 0.2, 0.4  # the ranges over the sensor's 10
    want[32:64] = 0.0
    want[32], want[48] = -1.0 / 1.5, 1.0  # the change over 1.5, clipped to +-1
    want[64:] = [math.cos(off), math.sin(off), 0.25]  # reach 2.5 over the range
    np.testing.assert_allclose(x, want, atol=1e-12)
    # turned back by the frame's 9 rays, the direction seen is the world's
    np.testing.assert_allclose(to_world(x[64:66], 9, 32), direction / 3.0, atol=1e-12)


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


def _forward(layers, x: np.ndarray) -> np.ndarray:  # type: ignore[no-untyped-def]
    """The actor as the module's docstring says it: dense layers, tanh between them, the
    mean clipped to [-1, 1] per component, then to norm 1."""
    h = x
    for i, (w, b) in enumerate(layers):
        h = w @ h + b
        if i < len(layers) - 1:
            h = np.tanh(h)
    h = np.clip(h, -1.0, 1.0)
    return h / max(1.0, float(np.hypot(h[0], h[1])))


@pytest.mark.parametrize("net", [(16, 16), (8,), (5, 7, 3)])
def test_the_numpy_policy_is_the_network_written_out(net: tuple[int, ...]) -> None:
    """The compiled forward pass and the batch one give the network's own output,
    computed here layer by layer; large inputs and a strong last layer drive the
    output into its clips."""
    layers = _random_policy(3, net).layers
    policy = PolicyWeights((*layers[:-1], (4.0 * layers[-1][0], layers[-1][1])))
    rng = np.random.default_rng(1)
    x = np.vstack([rng.uniform(-1, 1, (30, 67)), rng.uniform(-20, 20, (30, 67))])
    want = np.array([_forward(policy.layers, xi) for xi in x])
    norm = np.hypot(*want.T)
    assert np.isclose(norm, 1.0).any() and (norm < 0.99).any()  # clipped, and not
    np.testing.assert_allclose([policy.act(xi) for xi in x], want, rtol=0, atol=1e-12)
    np.testing.assert_allclose(policy.act_batch(x), want, rtol=0, atol=1e-12)
    with pytest.raises(ValueError, match=r"an observation of shape \(67,\) was expected"):
        policy.act(np.zeros(66))


def test_the_agent_acts_with_the_policy_in_the_direction_s_frame() -> None:
    """PPOAgent at level sensor: the features of its reading and the goal's direction,
    the network's velocity turned back to the world by the frame's rays; its second
    step sees the reading's change since the first."""
    policy = _random_policy(2)
    agent = PPOAgent(policy=policy)
    agent.reset(Task("sensor", 0.3, 0.5, 32, 10.0))
    rng = np.random.default_rng(5)
    first, second = rng.uniform(0.5, 10.0, 32), rng.uniform(0.5, 10.0, 32)
    goal = np.array([-3.0, 4.0])
    k = direction_frame(goal, 32)
    for prev, now in ((None, first), (first, second)):
        v = agent.act(Observation(ranges=now.copy(), goal=goal))
        want = to_world(_forward(policy.layers, features(now, prev, goal, 5.0, 10.0)), k, 32)
        np.testing.assert_allclose(v, want, rtol=0, atol=1e-12)


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
