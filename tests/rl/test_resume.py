"""Resumed training is the training that was not interrupted (bitwise), and a checkpoint
that is not one of the run's is refused in one line, whatever is wrong with it."""

from __future__ import annotations

import hashlib
import json
import re
import shutil
from pathlib import Path
from typing import Any

import pytest

from copi.errors import Interrupted, InvalidArgumentError


def _config(**kw: Any) -> Any:
    from copi.rl import TrainConfig

    base = {"families": ("star", "crowd"), "steps": 1536, "envs": 3, "n_steps": 128,
            "batch_size": 64, "n_epochs": 2, "net": (16, 16)}  # fmt: skip
    return TrainConfig(**{**base, **kw})


def _digest(path: Path) -> str:
    from copi.baselines import load_policy

    h = hashlib.sha256()
    for w, b in load_policy(path).layers:
        h.update(w.tobytes() + b.tobytes())
    return h.hexdigest()


def _train(out: Path, ckpt: Path | None = None, **kw: Any) -> Any:
    from copi.rl import train

    return train(_config(), out, checkpoints=ckpt, validate_every=500, validation_episodes=2,
                 **kw)  # fmt: skip


def test_a_resumed_run_gives_the_weights_of_an_uninterrupted_one(tmp_path: Path) -> None:
    pytest.importorskip("torch")
    pytest.importorskip("stable_baselines3")
    _train(tmp_path / "whole.npz")

    def stop(done: int, total: int) -> None:
        if done >= 1000:
            raise KeyboardInterrupt

    with pytest.raises(Interrupted, match=r"steps checkpointed in .*; rerun the same command"):
        _train(tmp_path / "cut.npz", tmp_path / "ck", progress=stop)
    assert not (tmp_path / "cut.npz").exists()
    saved = json.loads((tmp_path / "ck" / "last.json").read_text())["steps"]
    assert 0 < saved < 1536
    counts: list[tuple[int, int]] = []
    resumed: list[int] = []
    _train(tmp_path / "cut.npz", tmp_path / "ck", progress=lambda d, t: counts.append((d, t)),
           resumed=resumed.append)  # the same command again  # fmt: skip
    assert _digest(tmp_path / "cut.npz") == _digest(tmp_path / "whole.npz")
    assert resumed == [saved] and counts[0] == (saved, 1536) and counts[-1] == (1536, 1536)


def test_a_resumed_sac_run_gives_the_weights_of_an_uninterrupted_one(tmp_path: Path) -> None:
    """SAC's checkpoint holds its replay buffer, its entropy coefficient and the warm-up's
    generator: resumed mid-warm-up or after it, the weights are those of a run that was
    never stopped."""
    pytest.importorskip("torch")
    pytest.importorskip("stable_baselines3")
    from copi.rl import train

    cfg = _config(algorithm="sac", steps=900, buffer_size=600, learning_starts=300,
                  batch_size=32)  # the buffer wraps: 900 steps into 600  # fmt: skip
    assert cfg.planned_steps == 900 and cfg.identity()["algorithm"] == "sac"
    assert "buffer_size" not in _config().identity()  # PPO's identity as before SAC

    def go(out: Path, ckpt: Path | None = None, **kw: Any) -> Any:
        return train(cfg, out, checkpoints=ckpt, validate_every=200, validation_episodes=1,
                     **kw)  # fmt: skip

    go(tmp_path / "whole.npz")
    for cut in (250, 700):  # before learning starts, and after the buffer wrapped
        ck = tmp_path / f"ck{cut}"

        def stop(done: int, total: int, cut: int = cut) -> None:
            if done >= cut:
                raise KeyboardInterrupt

        with pytest.raises(Interrupted):
            go(tmp_path / f"cut{cut}.npz", ck, progress=stop)
        meta = json.loads((ck / "last.json").read_text())
        assert 0 < meta["steps"] < 900 and set(meta["buffer"]) == {"pos", "full"}
        go(tmp_path / f"cut{cut}.npz", ck)
        assert _digest(tmp_path / f"cut{cut}.npz") == _digest(tmp_path / "whole.npz")
    # a spoilt buffer position is refused in one line
    meta = json.loads((tmp_path / "ck700" / "last.json").read_text())
    meta["buffer"]["pos"] += 1
    (tmp_path / "ck700" / "last.json").write_text(json.dumps(meta))
    with pytest.raises(InvalidArgumentError, match=r"last.json's buffer is .*; expected where "
                       "a buffer of 200 rows writes"):  # fmt: skip
        go(tmp_path / "again.npz", tmp_path / "ck700")


def test_progress_counts_the_whole_rollouts_a_run_takes(tmp_path: Path) -> None:
    pytest.importorskip("torch")
    pytest.importorskip("stable_baselines3")
    from copi.rl import train

    cfg = _config(steps=500)  # rollouts of 3 x 128: 768 steps
    assert cfg.planned_steps == 768
    counts: list[tuple[int, int]] = []
    summary = train(cfg, tmp_path / "p.npz", validate_every=10_000, validation_episodes=1,
                    progress=lambda d, t: counts.append((d, t)))  # fmt: skip
    assert summary["steps"] == 768 and {t for _, t in counts} == {768}
    assert max(d for d, _ in counts) == 768


@pytest.fixture(scope="module")
def checkpoint(tmp_path_factory: pytest.TempPathFactory) -> Path:
    pytest.importorskip("torch")
    pytest.importorskip("stable_baselines3")
    d = tmp_path_factory.mktemp("ck")

    def stop(done: int, total: int) -> None:
        if done >= 1000:
            raise KeyboardInterrupt

    with pytest.raises(Interrupted):
        _train(d / "p.npz", d / "ck", progress=stop)
    return d / "ck"


def _json(ck: Path, change: Any) -> None:
    meta = json.loads((ck / "last.json").read_text())
    (ck / "last.json").write_text(json.dumps(change(meta)))


def _text(ck: Path, old: str, new: str) -> None:
    """Replace ``old`` in last.json's text (for what json.dumps cannot write: an integer
    of thousands of digits)."""
    text = (ck / "last.json").read_text()
    assert old in text
    (ck / "last.json").write_text(text.replace(old, new, 1))


def _sign(ck: Path) -> None:
    """last.json's digest made that of last.pt as it now is: a checkpoint whole but
    wrong within."""
    digest = hashlib.sha256((ck / "last.pt").read_bytes()).hexdigest()
    _json(ck, lambda m: {**m, "last_pt_sha256": digest})


def _pt(ck: Path, data: bytes) -> None:
    (ck / "last.pt").write_bytes(data)
    _sign(ck)


def _tensors(ck: Path, change: Any) -> None:
    import torch

    t = torch.load(ck / "last.pt", weights_only=True)
    torch.save(change(t), ck / "last.pt")
    _sign(ck)


def _nan(t: dict[str, Any]) -> dict[str, Any]:
    key = next(iter(t["params"]["policy"]))
    t["params"]["policy"][key] = t["params"]["policy"][key] * float("nan")
    return t


def _shapes(t: dict[str, Any]) -> dict[str, Any]:
    import torch

    key = next(iter(t["params"]["policy"]))
    t["params"]["policy"][key] = torch.zeros(3, 3)
    return t


class _Thing:  # something weights_only refuses to unpickle
    pass


def _point(m: dict[str, Any], i: int, **change: Any) -> dict[str, Any]:
    curve = [dict(c) for c in m["curve"]]
    curve[i].update(change)
    return {**m, "curve": curve}


def _env(m: dict[str, Any], **change: Any) -> dict[str, Any]:
    return {**m, "envs": [{**m["envs"][0], **change}, *m["envs"][1:]]}


_LONG = "9" * 5000
# The checkpoint (the fixture's): 768 steps, 2 rollouts of 3 envs x 128 steps, 2 epochs
# each (4 updates), in a run of 1,536 steps; its curve one point.
CASES = [
    (lambda ck: (ck / "last.json").write_text("{junk"), "last.json is not JSON"),
    (lambda ck: (ck / "last.json").write_text(""), "last.json is not JSON"),
    (lambda ck: (ck / "last.json").write_text("[1, 2]"), "last.json is not an object"),
    # an integer longer than Python converts: named where it is, whatever the field
    (lambda ck: _text(ck, '"updates": 4', '"updates": ' + _LONG),
     "last.json's updates is an integer of 5,000 digits; expected at most 40"),
    (lambda ck: _text(ck, '"seed": 0', '"seed": -' + _LONG),
     "last.json's config.seed is an integer of 5,000 digits"),
    (lambda ck: _text(ck, '"numpy_rng": ["MT19937", [', '"numpy_rng": ["MT19937", [' + _LONG + ","),
     "last.json's numpy_rng[1][0] is an integer of 5,000 digits"),
    (lambda ck: _json(ck, lambda m: {k: v for k, v in m.items() if k != "curve"}),
     "last.json's curve is missing; expected a learning curve of 1 to 2 points"),
    (lambda ck: _json(ck, lambda m: {**m, "reward_norm": {**m["reward_norm"], "var": -1.0}}),
     "last.json's reward_norm is"),
    (lambda ck: _json(ck, lambda m: {k: v for k, v in m.items() if k != "reward_norm"}),
     "last.json's reward_norm is missing; expected the reward's running mean"),
    (lambda ck: _json(ck, lambda m: {**m, "reward_norm": {**m["reward_norm"], "returns": [1.0]}}),
     "the 3 environments' returns"),
    (lambda ck: _json(ck, lambda m: {**m, "curve": []}), "last.json's curve is []"),
    (lambda ck: _json(ck, lambda m: {**m, "steps": 10**12}),
     "last.json's steps is 1000000000000; expected a whole number of rollouts of 384 steps "
     "(3 envs x 128), at most the run's 1,536"),
    (lambda ck: _json(ck, lambda m: {**m, "steps": -5}), "last.json's steps is -5"),
    (lambda ck: _json(ck, lambda m: {**m, "steps": 1000}), "last.json's steps is 1000"),
    (lambda ck: _json(ck, lambda m: {**m, "steps": 1920}), "last.json's steps is 1920"),
    (lambda ck: _json(ck, lambda m: {**m, "steps": 768.0}), "last.json's steps is 768.0"),
    (lambda ck: _json(ck, lambda m: {**m, "steps": 0}), "last.json's steps is 0"),
    (lambda ck: _json(ck, lambda m: {**m, "updates": "x"}),
     "last.json's updates is 'x'; expected 4 (2 rollouts of 2 epochs)"),
    (lambda ck: _json(ck, lambda m: {**m, "updates": None}), "last.json's updates is None"),
    (lambda ck: _json(ck, lambda m: {k: v for k, v in m.items() if k != "updates"}),
     "last.json's updates is missing"),
    (lambda ck: _json(ck, lambda m: {**m, "updates": 1e300}), "last.json's updates is 1e+300"),
    (lambda ck: _json(ck, lambda m: {**m, "updates": -7}), "last.json's updates is -7"),
    (lambda ck: _json(ck, lambda m: {**m, "updates": 6}), "last.json's updates is 6"),
    (lambda ck: _json(ck, lambda m: {**m, "updates": True}), "last.json's updates is True"),
    (lambda ck: _json(ck, lambda m: {**m, "seconds": float("nan")}),
     "last.json's seconds is nan; expected a wall time in 0 .. 31,536,000 s (a year)"),
    (lambda ck: _json(ck, lambda m: {**m, "seconds": 1e308}), "last.json's seconds is 1e+308"),
    (lambda ck: _json(ck, lambda m: {**m, "seconds": -1}), "last.json's seconds is -1"),
    (lambda ck: _json(ck, lambda m: {**m, "seconds": 4e7}), "last.json's seconds is 40000000.0"),
    (lambda ck: _json(ck, lambda m: _point(m, 0, success=7)),
     "last.json's curve[0].success is 7; expected a fraction of episodes in [0, 1]"),
    (lambda ck: _json(ck, lambda m: _point(m, 0, success=-0.5)),
     "last.json's curve[0].success is -0.5"),
    (lambda ck: _json(ck, lambda m: _point(m, 0, success="all")),
     "last.json's curve[0].success is 'all'"),
    (lambda ck: _json(ck, lambda m: _point(m, 0, seconds=1e308)),
     "last.json's curve[0].seconds is 1e+308"),
    (lambda ck: _json(ck, lambda m: _point(m, 0, steps=1152)),
     "last.json's curve[0].steps is 1152; expected a whole number of rollouts of 384 steps, "
     "more than the point before's 0 and at most the checkpoint's 768"),
    (lambda ck: _json(ck, lambda m: _point(m, 0, steps=384)),
     "last.json's curve[0].steps is 384; expected the checkpoint's steps, 768"),
    (lambda ck: _json(ck, lambda m: {**m, "curve": [m["curve"][0], m["curve"][0]]}),
     "last.json's curve[1].steps is 768; expected a whole number of rollouts of 384 steps, "
     "more than the point before's 768"),
    (lambda ck: _json(ck, lambda m: {**m, "curve": [{"steps": 768}]}),
     "last.json's curve[0] is {'steps': 768}; expected a point of steps, seconds and success"),
    (lambda ck: _json(ck, lambda m: {**m, "envs": m["envs"][:1]}),
     "last.json's envs is [{'drawn_from'"),
    (lambda ck: _json(ck, lambda m: _env(m, ended="exploded")),
     "last.json's envs[0].ended is 'exploded'; expected null, terminated or truncated"),
    (lambda ck: _json(ck, lambda m: _env(m, drawn_from={"bit_generator": "MT19937"})),
     "last.json's envs[0].drawn_from is {'bit_generator': 'MT19937'}; expected a PCG64"),
    (lambda ck: _json(ck, lambda m: {**m, "numpy_rng": m["numpy_rng"][:2]}),
     "last.json's numpy_rng is ['MT19937'"),
    (lambda ck: _json(ck, lambda m: {**m, "python_rng": [3, [], None]}),
     "last.json's python_rng is [3, [], None]; expected Python's random state"),
    (lambda ck: _json(ck, lambda m: {**m, "config": {**m["config"], "steps": "x"}}),
     "last.json's config.steps is 'x'"),
    (lambda ck: _json(ck, lambda m: {**m, "last_pt_sha256": 7}),
     "last.json's last_pt_sha256 is 7; expected a SHA-256 digest"),
    # last.pt of another moment than last.json's (a write cut short between the two)
    (lambda ck: (ck / "last.pt").write_bytes((ck / "last.pt").read_bytes() + b"\0"),
     "last.pt is not the file last.json was written with"),
    (lambda ck: _pt(ck, (ck / "last.pt").read_bytes()[:300]), "last.pt cannot be read"),
    (lambda ck: _pt(ck, b"junk" * 100), "last.pt cannot be read"),
    (lambda ck: _pt(ck, b""), "last.pt cannot be read"),
    (lambda ck: _tensors(ck, lambda t: _Thing()), "last.pt cannot be read"),
    (lambda ck: _tensors(ck, lambda t: {"params": t["params"]}), "lacks parts of a checkpoint"),
    (lambda ck: _tensors(ck, _nan), "holds NaN or infinity"),
    (lambda ck: _tensors(ck, _shapes), "does not fit this run"),
    (lambda ck: (ck / "last.json").unlink(), "no such checkpoint file"),
]  # fmt: skip


@pytest.mark.parametrize(("spoil", "message"), CASES)
def test_a_spoilt_checkpoint_is_refused_in_one_line(
    checkpoint: Path, tmp_path: Path, spoil: Any, message: str
) -> None:
    ck = tmp_path / "ck"
    shutil.copytree(checkpoint, ck)
    spoil(ck)
    before = {p.name: p.read_bytes() for p in ck.iterdir()}
    with pytest.raises(InvalidArgumentError, match=re.escape(message)) as err:
        _train(tmp_path / "p.npz", ck)
    assert "\n" not in str(err.value) and not (tmp_path / "p.npz").exists()
    assert str(ck) in str(err.value)
    assert {p.name: p.read_bytes() for p in ck.iterdir()} == before  # left as it was


def test_a_checkpoint_without_the_digest_of_last_pt_resumes(checkpoint: Path,
                                                             tmp_path: Path) -> None:  # fmt: skip
    """Checkpoints written before last.json held last.pt's digest resume as before."""
    ck = tmp_path / "ck"
    shutil.copytree(checkpoint, ck)
    _json(ck, lambda m: {k: v for k, v in m.items() if k != "last_pt_sha256"})
    resumed: list[int] = []
    summary = _train(tmp_path / "p.npz", ck, resumed=resumed.append)
    assert resumed == [768] and summary["steps"] == 1536
    assert "last_pt_sha256" in json.loads((ck / "last.json").read_text())


def test_a_checkpoint_from_before_curricula_resumes_as_before(checkpoint: Path,
                                                               tmp_path: Path) -> None:  # fmt: skip
    """Environments' states written before they named the families their episode was
    drawn from (curricula) resume as before: to the weights of the run not stopped."""
    ck = tmp_path / "ck"
    shutil.copytree(checkpoint, ck)
    _json(ck, lambda m: {**m, "envs": [{k: v for k, v in e.items() if k != "drawn_families"}
                                       for e in m["envs"]]})  # fmt: skip
    assert "drawn_families" not in (ck / "last.json").read_text()
    resumed: list[int] = []
    _train(tmp_path / "cut.npz", ck, resumed=resumed.append)
    _train(tmp_path / "whole.npz")
    assert resumed == [768]
    assert _digest(tmp_path / "cut.npz") == _digest(tmp_path / "whole.npz")
