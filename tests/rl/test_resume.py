"""Resumed training is the training that was not interrupted (bitwise), and a checkpoint
that is not one of the run's is refused in one line, whatever is wrong with it."""

from __future__ import annotations

import hashlib
import json
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


def _tensors(ck: Path, change: Any) -> None:
    import torch

    t = torch.load(ck / "last.pt", weights_only=True)
    torch.save(change(t), ck / "last.pt")


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


CASES = [
    (lambda ck: (ck / "last.json").write_text("{junk"), "last.json is not JSON"),
    (lambda ck: (ck / "last.json").write_text(""), "last.json is not JSON"),
    (lambda ck: (ck / "last.json").write_text("[1, 2]"), "last.json is not an object"),
    (lambda ck: _json(ck, lambda m: {k: v for k, v in m.items() if k != "curve"}),
     "its learning curve is missing"),
    (lambda ck: _json(ck, lambda m: {**m, "steps": 10**12}), "it claims 1000000000000 steps"),
    (lambda ck: _json(ck, lambda m: {**m, "steps": -5}), "it claims -5 steps"),
    (lambda ck: _json(ck, lambda m: {**m, "seconds": float("nan")}), "its wall time is nan"),
    (lambda ck: _json(ck, lambda m: {**m, "envs": m["envs"][:1]}),
     "another number of environments"),
    (lambda ck: (ck / "last.pt").write_bytes((ck / "last.pt").read_bytes()[:300]),
     "last.pt cannot be read"),
    (lambda ck: (ck / "last.pt").write_bytes(b"junk" * 100), "last.pt cannot be read"),
    (lambda ck: (ck / "last.pt").write_bytes(b""), "last.pt cannot be read"),
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
    with pytest.raises(InvalidArgumentError, match=message) as err:
        _train(tmp_path / "p.npz", ck)
    assert "\n" not in str(err.value) and not (tmp_path / "p.npz").exists()
