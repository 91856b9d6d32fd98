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
    from copi.baselines._ppo import OBSERVATION_V3, POLICIES, load_policy, observation_size

    files = sorted(POLICIES.glob("*.npz")) + sorted((POLICIES / "seeds").glob("*.npz"))
    assert len(files) >= 7
    for path in files:
        policy = load_policy(path)
        command = policy.info.get("command", "")
        algo = path.stem.split("-")[0]  # ppo-..., sac-... or clone-...
        if algo == "clone":  # no RL: a classifier of its demonstrator's moves
            assert command.startswith("copi rl train --algo clone --imitate compass-guard ")
            assert f" -o results/rl/{path.stem}-s0.npz" in command and " --seed 0" in command
            assert policy.output == "compass" and "steps" not in policy.info
            continue
        assert algo in ("ppo", "sac") and command.startswith(
            f"copi rl train -o results/rl/{algo}-"), (path.name, command)  # fmt: skip
        assert " --seed " in command and (" --algo sac " in command) == (algo == "sac")
        # PPO 2M steps; SAC, and PPO warm-started by imitation, 1M
        cloned = " --imitate " in command
        assert f" --steps {2000000 if algo == 'ppo' and not cloned else 1000000} " in command
        assert cloned == path.stem.startswith("ppo-il-")
        # a curriculum's stages are in the command and in the run's identity alike
        staged = path.stem.startswith("ppo-cur-")
        assert (" --curriculum " in command) == staged == ("curriculum" in policy.info)
        if staged:
            stages = ",".join(f"{f}:{end}" for f, end in policy.info["curriculum"])
            assert f" --curriculum {stages} " in command
        if " --task chauffeur " in command and " --levels sensor" in command:
            # an evader at the game's level: it reads no static reading
            assert policy.level == "sensor"
            assert policy.size == observation_size(32, OBSERVATION_V3, "sensor", policy.frames)
        if path.parent.name == "seeds":
            seed = path.stem.rsplit("-s", 1)[1]
            assert command.endswith(f"--seed {seed}") and seed != "0"


def _random_v3(level: str, frames: int, seed: int = 0) -> PolicyWeights:
    from copi.baselines._ppo import OBSERVATION_V3, observation_size

    rng = np.random.default_rng(seed)
    sizes = [observation_size(32, OBSERVATION_V3, level, frames), 16, 2]
    layers = tuple((rng.normal(0, 0.5, (b, a)), rng.normal(0, 0.1, b))
                   for a, b in zip(sizes, sizes[1:], strict=False))  # fmt: skip
    return PolicyWeights(layers, observation=OBSERVATION_V3, level=level, frames=frames)


def test_v3_features_are_the_level_s_reading_stacked_in_the_direction_s_frame() -> None:
    """Worked out block by block: the reading, the hits the static reading does not
    explain (map only), each step's change (zeros before the episode's first reading),
    the agent's velocity, the direction and the reach, all turned by the frame's k rays."""
    from copi.baselines import features_v3

    rng = np.random.default_rng(3)
    r, h1 = rng.uniform(0.5, 10, 32), rng.uniform(0.5, 10, 32)
    static = r + np.where(rng.random(32) < 0.3, rng.uniform(0, 4, 32), 0.0)
    d = np.array([math.cos(1.0), math.sin(1.0)])  # 1 rad: k = round(32 / 2pi) = 5 rays
    k = direction_frame(d, 32)
    assert k == 5
    v = np.array([0.0, -0.5])
    x = features_v3(r, [h1], static, v, d, 30.0, 10.0, 4)
    assert x.shape == (32 * 5 + 5,)  # reading, unexplained, 3 changes, then 5
    np.testing.assert_allclose(x[:32], np.roll(r, -k) / 10)
    np.testing.assert_allclose(x[32:64], np.roll(static - r, -k) / 10, atol=1e-12)
    np.testing.assert_allclose(x[64:96], np.roll(np.clip(r - h1, -1.5, 1.5) / 1.5, -k))
    np.testing.assert_array_equal(x[96:160], 0.0)  # readings before the first: no change
    np.testing.assert_allclose(to_world(x[160:162], k, 32), v, atol=1e-12)
    np.testing.assert_allclose(to_world(x[162:164], k, 32), d, atol=1e-12)
    assert x[164] == 1.0  # the reach, clipped to the range
    at_sensor = features_v3(r, [h1], None, v, d, 30.0, 10.0, 4)
    np.testing.assert_allclose(at_sensor, np.r_[x[:32], x[64:]])  # no unexplained block


@pytest.mark.parametrize("j", [1, 7, 20])
def test_the_v3_frame_is_a_symmetry(j: int) -> None:
    """Turning the world, its readings, velocity and direction by j whole rays leaves
    the v3 observation as it was."""
    from copi.baselines import features_v3

    rng = np.random.default_rng(j)
    r, h1, h2 = (rng.uniform(0.5, 10, 32) for _ in range(3))
    static = r + rng.uniform(0, 2, 32)
    a = 2 * math.pi * j / 32
    turn = np.array([[math.cos(a), -math.sin(a)], [math.sin(a), math.cos(a)]])
    d, v = np.array([0.6, -0.8]), np.array([0.3, 0.1])
    x = features_v3(r, [h1, h2], static, v, d, 3.0, 10.0, 3)
    y = features_v3(np.roll(r, j), [np.roll(h1, j), np.roll(h2, j)], np.roll(static, j),
                    turn @ v, turn @ d, 3.0, 10.0, 3)  # fmt: skip
    np.testing.assert_allclose(x, y, atol=1e-9)


def test_a_v3_agent_runs_at_its_level_and_remembers_what_it_saw() -> None:
    """A map policy is a map method (refused at sensor, naming its level); each step it
    sees its earlier readings and the velocity it chose last, as the training env
    shows them."""
    from copi.baselines import features_v3
    from copi.runs import Episode

    policy = _random_v3("map", 3, seed=4)
    agent = PPOAgent(policy=policy)
    assert agent.sensing == "map"
    episode = Episode.draw("star", 0, 1)
    with pytest.raises(ValueError, match="map"):
        episode.run(agent, sensing="sensor")
    agent.reset(Task("map", 0.3, 0.5, 32, 10.0))
    rng = np.random.default_rng(6)
    seen: list[np.ndarray] = []
    last = np.zeros(2)
    goal = np.array([4.0, 3.0])
    for _ in range(4):
        r = rng.uniform(0.5, 10, 32)
        static = r + 1.0
        v = agent.act(Observation(ranges=r, goal=goal, position=np.zeros(2), static=static))
        x = features_v3(r, seen, static, last, goal, math.hypot(*goal), 10.0, 3)
        want = to_world(_forward(policy.layers, x), direction_frame(goal, 32), 32)
        np.testing.assert_allclose(v, want, atol=1e-12)
        seen, last = [r, *seen][:2], v
    out = episode.run(PPOAgent(policy=policy), sensing="map")
    assert out.steps >= 1


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"frames": 99}, "'frames' must be an int in 2 .. 16"),
        ({"level": "oracle"}, "'level' must be sensor or map"),
        ({"level": "sensor"}, "layer 0 takes 133 inputs; expected the observation's 101"),
        ({"frames": 4}, "layer 0 takes 133 inputs; expected the observation's 165"),
        ({"output": "relu"}, "metadata 'output' must be one of clip, tanh, compass; got 'relu'"),
    ],
)
def test_v3_policy_files_round_trip_and_refuse_another_layout(
    change: dict[str, object], message: str, tmp_path: Path
) -> None:
    policy = _random_v3("map", 3)
    path = save_policy(policy, tmp_path / "p.npz")
    back = load_policy(path)
    assert (back.observation, back.level, back.frames) == ("copi-local-v3", "map", 3)
    x = np.random.default_rng(0).uniform(-1, 1, (5, 133))
    np.testing.assert_array_equal(back.act_batch(x), policy.act_batch(x))
    with pytest.raises(PolicyFormatError, match=message):
        load_policy(_tamper(path, tmp_path / "bad.npz", **change))


def test_weights_of_float32_values_are_stored_in_float32_and_read_back_exactly(
    tmp_path: Path,
) -> None:
    """A network trained in float32 takes half the bytes on disk and loses nothing; one
    of other values keeps float64."""
    single = _random_policy(3)
    single = PolicyWeights(tuple((w.astype(np.float32).astype(np.float64),
                                  b.astype(np.float32).astype(np.float64))
                                 for w, b in single.layers))  # fmt: skip
    for policy, kind in ((single, np.float32), (_random_policy(3), np.float64)):
        path = save_policy(policy, tmp_path / f"{kind.__name__}.npz")
        with np.load(path) as z:
            assert z["w0"].dtype == kind
        back = load_policy(path)
        for (w, b), (w2, b2) in zip(policy.layers, back.layers, strict=True):
            np.testing.assert_array_equal(w, w2)
            np.testing.assert_array_equal(b, b2)
