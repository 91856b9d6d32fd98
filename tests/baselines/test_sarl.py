"""SARL (CrowdNav's peer): its state's frame, its lookahead against a brute-force sweep,
its attention's order-blindness, numpy against torch, its file's refusals, and a short
training whose value tells states that end in contact from states that reach the goal."""

from __future__ import annotations

import json
import math
import zipfile
from pathlib import Path

import numpy as np
import pytest

from copi.baselines import SARLAgent, SARLFormatError, SARLWeights, load_sarl, save_sarl
from copi.baselines._sarl import (
    HUMAN,
    NETS,
    SELF,
    WIDTHS,
    SARLReward,
    lookahead_states,
    sarl_actions,
    sarl_state,
    sarl_values,
    wall_free,
)
from copi.core import Observation
from copi.testing import check_agent


def random_weights(seed: int = 0, n_rays: int = 32) -> SARLWeights:
    rng = np.random.default_rng(seed)
    e = WIDTHS["mlp1"][-1]
    ins = {"mlp1": SELF + HUMAN, "mlp2": e, "attention": 2 * e,
           "mlp3": SELF + n_rays + WIDTHS["mlp2"][-1]}  # fmt: skip
    nets = {}
    for name in NETS:
        layers, n_in = [], ins[name]
        for w in WIDTHS[name]:
            layers.append((rng.normal(0, 1 / math.sqrt(n_in), (n_in, w)), rng.normal(0, 0.1, w)))
            n_in = w
        nets[name] = layers
    return SARLWeights(nets, n_rays)


def scene(rng: np.random.Generator, discs: int = 5) -> tuple[Observation, np.ndarray]:
    pos = rng.uniform(-5, 5, 2)
    o = np.column_stack([pos + rng.uniform(-8, 8, (discs, 2)), rng.uniform(-0.8, 0.8, (discs, 2)),
                         rng.uniform(0.5, 1.0, discs)])  # fmt: skip
    obs = Observation(ranges=rng.uniform(1, 10, 32), goal=rng.uniform(-20, 20, 2), position=pos,
                      static=rng.uniform(1, 10, 32), obstacles=o)  # fmt: skip
    return obs, rng.normal(size=2)


def turned(obs: Observation, d: np.ndarray, k: int) -> tuple[Observation, np.ndarray]:
    """The same scene turned by k rays about the robot."""
    a = 2 * math.pi * k / 32
    rot = np.array([[math.cos(a), -math.sin(a)], [math.sin(a), math.cos(a)]])
    o = obs.obstacles.copy()
    o[:, :2] = (o[:, :2] - obs.position) @ rot.T + obs.position
    o[:, 2:4] = o[:, 2:4] @ rot.T
    return Observation(ranges=np.roll(obs.ranges, k), goal=obs.goal @ rot.T, position=obs.position,
                       static=np.roll(obs.static, k), obstacles=o), d @ rot.T  # fmt: skip


def test_actions_are_crowdnavs_holonomic_set() -> None:
    a = sarl_actions()
    speeds = np.hypot(a[:, 0], a[:, 1])
    assert a.shape == (81, 2) and speeds.max() == pytest.approx(1.0) and speeds[-1] == 0.0
    assert np.allclose(np.unique(speeds.round(9))[1:], [(math.exp(i / 5) - 1) / (math.e - 1)
                                                         for i in range(1, 6)])  # fmt: skip


@pytest.mark.parametrize("k", [1, 5, 16, 31])
def test_the_state_is_the_same_in_a_scene_turned_by_whole_rays(k: int) -> None:
    rng = np.random.default_rng(k)
    obs, d = scene(rng)
    v = rng.uniform(-0.5, 0.5, 2)
    k0, me, h, st = sarl_state(obs, d, 7.0, v, 0.3, 10.0)
    obs2, d2 = turned(obs, d, k)
    a = 2 * math.pi * k / 32
    v2 = np.array([[math.cos(a), -math.sin(a)], [math.sin(a), math.cos(a)]]) @ v
    k2, me2, h2, st2 = sarl_state(obs2, d2, 7.0, v2, 0.3, 10.0)
    assert k2 == (k0 + k) % 32
    np.testing.assert_allclose(me2, me, atol=1e-12)
    np.testing.assert_allclose(h2, h, atol=1e-12)
    np.testing.assert_array_equal(st2, st)


def test_the_state_holds_the_nearest_discs_within_range_nearest_first() -> None:
    obs, d = scene(np.random.default_rng(3), discs=20)
    _, _, h, _ = sarl_state(obs, d, 5.0, np.zeros(2), 0.3, 10.0)
    o = obs.obstacles
    dist = np.hypot(*(o[:, :2] - obs.position).T)
    want = np.sort(dist[dist - o[:, 4] < 10.0])[:8]
    np.testing.assert_allclose(h[:, 5] * 10.0, want)


def test_the_lookahead_gap_is_the_closest_approach_of_both_moves() -> None:
    rng = np.random.default_rng(4)
    for _ in range(20):
        obs, d = scene(rng, discs=4)
        _, me, h, _ = sarl_state(obs, d, 5.0, np.zeros(2), 0.3, 10.0)
        a = sarl_actions()
        _, h2, gap, end = lookahead_states(me, h, a, 10.0)
        tau = np.linspace(0.0, 1.0, 2001)
        for i in rng.choice(len(a), 6, replace=False):
            rel = h[None, :, :2] * 10.0 + tau[:, None, None] * (h[None, :, 2:4] - a[i])
            brute = (np.hypot(rel[..., 0], rel[..., 1]) - h[None, :, 6]).min()
            assert gap[i] == pytest.approx(brute, abs=1e-5)
            np.testing.assert_allclose(h2[i, :, :2] * 10.0, h[:, :2] * 10.0 + h[:, 2:4] - a[i])
            assert end[i] == pytest.approx((np.hypot(*rel[-1].T) - h[:, 6]).min())


def test_a_move_into_a_wall_is_not_considered() -> None:
    static = np.full(32, 1.0)
    static[0] = 0.1  # a wall 1 step ahead along +x (ranges over max range 10)
    a = np.array([[1.0, 0.0], [0.8, 0.0], [0.5, 0.0], [0.7, 0.1], [0.0, 1.0], [0.0, 0.0]])
    assert wall_free(static, a, 0.3, 10.0).tolist() == [False, False, True, False, True, True]


def test_the_value_ignores_the_order_of_the_discs_and_padding() -> None:
    w = random_weights()
    rng = np.random.default_rng(5)
    me, h, st = rng.normal(size=(3, SELF)), rng.normal(size=(3, 6, HUMAN)), rng.normal(size=32)
    perm = rng.permutation(6)
    np.testing.assert_allclose(sarl_values(w, me, h[:, perm], st), sarl_values(w, me, h, st),
                               rtol=1e-5)
    one = sarl_values(w, me, h[:, :1], st)
    assert not np.allclose(one, sarl_values(w, me, h, st))  # the other discs count


def test_numpy_inference_equals_torchs() -> None:
    torch = pytest.importorskip("torch")
    from copi.rl._sarl import SARLNet, export

    torch.manual_seed(1)
    net = SARLNet()
    w = export(net, SARLReward())
    rng = np.random.default_rng(6)
    for h in (0, 1, 5, 8):
        me, hum, st = rng.normal(size=(4, SELF)), rng.normal(size=(4, h, HUMAN)), rng.normal(
            size=(4, 32))  # fmt: skip
        pad = np.zeros((4, 8, HUMAN + 1))
        pad[:, :h, :HUMAN] = hum
        pad[:, :h, HUMAN] = 1.0
        t = net(*(torch.as_tensor(x, dtype=torch.float32) for x in (me, pad, st)))
        np.testing.assert_allclose(t.detach().numpy(), sarl_values(w, me, hum, st), atol=1e-5)


def test_the_weights_round_trip_and_bad_files_are_refused(tmp_path: Path) -> None:
    w = random_weights(2)
    path = save_sarl(w, tmp_path / "s.npz")
    back = load_sarl(path)
    me, h, st = np.ones((2, SELF)), np.ones((2, 3, HUMAN)), np.ones(32)
    np.testing.assert_allclose(sarl_values(back, me, h, st), sarl_values(w, me, h, st), rtol=1e-6)
    with zipfile.ZipFile(path) as z:
        members = {n: z.read(n) for n in z.namelist()}

    def spoilt(name: str, change: dict[str, bytes]) -> Path:
        p = tmp_path / name
        with zipfile.ZipFile(p, "w") as z:
            for n, b in {**members, **change}.items():
                z.writestr(n, b)
        return p

    def npy(a: np.ndarray) -> bytes:
        import io

        buf = io.BytesIO()
        np.save(buf, a)
        return buf.getvalue()

    bad = np.zeros((SELF + HUMAN, 64), dtype=np.float32)
    bad[0, 0] = np.nan
    meta = json.loads(np.load(path)["metadata"].item())
    cases = {
        "nan.npz": ({"mlp1_w0.npy": npy(bad)}, "NaN"),
        "shape.npz": ({"mlp1_w0.npy": npy(np.zeros((5, 64), np.float32))}, "takes 5 values"),
        "foreign.npz": ({"metadata.npy": npy(np.array(json.dumps({**meta, "format": "x"})))},
                        "format"),
        "missing.npz": ({"metadata.npy": npy(np.array(json.dumps(
            {**meta, "layers": {**meta["layers"], "mlp3": 4}})))}, "missing"),
        "huge.npz": ({"metadata.npy": npy(np.array(json.dumps(
            {**meta, "reward": {**meta["reward"], "progress": 10**400}})))}, "reward"),
    }  # fmt: skip
    for name, (change, words) in cases.items():
        with pytest.raises(SARLFormatError, match=words) as exc:
            load_sarl(spoilt(name, change))
        assert "\n" not in str(exc.value)
    (tmp_path / "junk.npz").write_bytes(b"not a zip")
    with pytest.raises(SARLFormatError, match="junk.npz"):
        load_sarl(tmp_path / "junk.npz")


def test_sarl_keeps_the_agent_contract() -> None:
    check_agent(lambda: SARLAgent(random_weights(3)), levels=["oracle"], episodes=2,
                max_steps=40)  # fmt: skip


def test_a_short_imitation_learns_the_demonstrators_returns() -> None:
    pytest.importorskip("torch")
    from copi.envs.local_policy import TRAINING_SEED
    from copi.methods import make_agent
    from copi.rl._sarl import SARLConfig, record_episodes, returns, train_sarl

    config = SARLConfig(demo_episodes=8, il_epochs=300, rl_episodes=0, validation_episodes=0)
    w, curve = train_sarl(config, log=lambda s: None)
    assert curve and w.info["config"]["demo_episodes"] == 8
    # the same demonstrations again (the simulator and the demonstrator are deterministic)
    seen, outcomes = record_episodes(lambda: make_agent("model-oracle"), range(8), "crowd",
                                     TRAINING_SEED)  # fmt: skip
    assert "collision" in outcomes and "success" in outcomes
    g = returns(seen.arrays(), config.reward)
    me, humans, static = (np.array(x) for x in (seen.me, seen.humans, seen.static))
    v = np.array([sarl_values(w, me[i : i + 1], humans[i : i + 1, : int(humans[i, :, HUMAN].sum()),
                                                         :HUMAN], static[i])[0]
                  for i in range(len(g))])  # fmt: skip
    assert np.mean((v - g) ** 2) < 0.25 * np.var(g)  # far better than their mean
    ends = np.flatnonzero(np.array(seen.end))
    hit = [i for i, o in zip(ends, outcomes, strict=True) if o == "collision"]
    assert np.mean(v[hit]) < np.median(v)  # the states just before a contact valued low


def test_every_shipped_sarl_network_loads_and_says_how_it_was_trained() -> None:
    from copi.baselines._sarl import SHIPPED

    for path in sorted(SHIPPED.glob("*.npz")):
        info = load_sarl(path).info
        assert info.get("command", "").startswith("python studies/sarl_train.py "), path.name
        assert 0.0 < info["validation"] <= 1.0 and info["config"]["family"] in path.stem


@pytest.mark.parametrize(("args", "words"), [
    (["--family", "castle"], "family must be one of"),
    (["--demonstrator", "dwa"], "must run at level oracle"),
    (["--demonstrator", "nosuch"], "nosuch"),
    (["--epsilon", "0.5,x"], "--epsilon must be three"),
    (["--epsilon", "2,0.1,10"], "epsilon must be"),
    (["--demo-episodes", "0"], "--demo-episodes"),
])  # fmt: skip
def test_bad_sarl_training_options_are_one_line_and_write_nothing(
    args: list[str], words: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from tests.cli.test_faults import _one_line_error, run

    line = _one_line_error(*run(["rl", "sarl", "-o", str(tmp_path / "s.npz"), *args],
                                capsys)[::2])  # fmt: skip
    assert words in line
    assert list(tmp_path.iterdir()) == []


def test_copi_rl_sarl_writes_a_network_copi_runs_and_its_curve(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    pytest.importorskip("torch")
    from tests.cli.test_faults import run

    out = tmp_path / "s.npz"
    code, stdout, err = run(["rl", "sarl", "-o", str(out), "--demo-episodes", "2",
                             "--il-epochs", "0", "--rl-episodes", "1",
                             "--validation-episodes", "2"], capsys)  # fmt: skip
    assert code == 0, err
    w = load_sarl(out)
    assert w.info["command"].startswith("copi rl sarl -o ") and "--rl-episodes 1" in w.info[
        "command"]  # fmt: skip
    curve = json.loads(out.with_suffix(".json").read_text())["curve"]
    assert [c["episodes"] for c in curve] == [0, 1]  # the last episode validated too
    assert out.with_suffix(".png").read_bytes()[:4] == b"\x89PNG"
    check_agent(lambda: SARLAgent(str(out)), levels=["oracle"], episodes=1, max_steps=20)


def test_the_state_keeps_the_direction_s_unit_vector_whatever_its_length() -> None:
    obs, d = scene(np.random.default_rng(9))
    _, me, h, st = sarl_state(obs, d, 5.0, np.zeros(2), 0.3, 10.0)
    _, me7, h7, st7 = sarl_state(obs, 7.3 * d, 5.0, np.zeros(2), 0.3, 10.0)
    assert np.hypot(*me[1:3]) == pytest.approx(1.0)
    np.testing.assert_allclose(me7, me, atol=1e-12)  # a rounding of the norm apart
    np.testing.assert_array_equal(h7, h)
