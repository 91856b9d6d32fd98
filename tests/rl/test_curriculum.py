"""A curriculum (``TrainConfig.curriculum``, ``--curriculum``): the training episodes'
families follow its stages, a resumed run goes on in its stage, bad stages are refused
in one line."""

from __future__ import annotations

import hashlib
import json
from pathlib import Path
from typing import Any

import pytest

from copi.errors import InvalidArgumentError
from copi.rl import TrainConfig
from tests.cli.test_faults import _one_line_error, run


def _config(**kw: Any) -> TrainConfig:
    base = {"families": ("crowd",), "steps": 1536, "envs": 3, "n_steps": 128,
            "batch_size": 64, "n_epochs": 2, "net": (16, 16), "max_steps": 20,
            "curriculum": (("star", 384), ("polygon", 768))}  # fmt: skip
    return TrainConfig(**{**base, **kw})


def test_the_stages_name_the_families_of_each_step() -> None:
    c = _config()
    assert [c.families_at(s) for s in (0, 383, 384, 767, 768, 1535)] == [
        ("star",), ("star",), ("polygon",), ("polygon",), ("crowd",), ("crowd",)]
    assert c.identity()["curriculum"] == [["star", 384], ["polygon", 768]]
    assert "curriculum" not in _config(curriculum=()).identity()  # as before curricula
    assert _config(curriculum=()).families_at(0) == ("crowd",)
    # the stages as a policy's info keeps them (lists) make the same config, hashable
    listed = _config(curriculum=[["star", 384], ["polygon", 768]])
    assert listed == c and hash(listed) == hash(c)


@pytest.mark.parametrize(("kw", "message"), [
    ({"curriculum": (("star", 384), ("polygon", 384))}, "increasing steps"),
    ({"curriculum": (("star", 2000),)}, "below steps"),
    ({"curriculum": (("nowhere", 100),)}, "family must be one of"),
    ({"curriculum": (("star", 1.5),)}, "must be \\(family, the step it ends at\\)"),
    ({"algorithm": "clone", "imitate": "compass-guard"}, "needs PPO or SAC"),
    ({"task": "chauffeur"}, "needs PPO or SAC on navigation"),
])  # fmt: skip
def test_bad_stages_are_refused(kw: dict[str, Any], message: str) -> None:
    with pytest.raises(InvalidArgumentError, match=message):
        _config(**kw)


@pytest.mark.parametrize(("flag", "message"), [
    ("star:x", "--curriculum must be FAMILY:STEP stages"),
    (":100", "--curriculum must be FAMILY:STEP stages"),
    ("star:300,polygon:200", "increasing steps"),
    (" , ", "--curriculum must be FAMILY:STEP stages"),
])  # fmt: skip
def test_bad_curricula_on_the_command_line_are_one_line(flag: str, message: str, tmp_path: Path,
                                                        capsys) -> None:  # fmt: skip
    out = tmp_path / "p.npz"
    code, _, err = run(["rl", "train", "-o", str(out), "--families", "crowd", "--steps",
                        "1000", "--curriculum", flag], capsys)  # fmt: skip
    assert message in _one_line_error(code, err)
    assert not list(tmp_path.iterdir())


def _digest(path: Path) -> str:
    from copi.baselines import load_policy

    h = hashlib.sha256()
    for w, b in load_policy(path).layers:
        h.update(w.tobytes() + b.tobytes())
    return h.hexdigest()


def test_the_episodes_follow_the_stages_and_a_resumed_run_its_stage(tmp_path: Path,
                                                                     monkeypatch) -> None:  # fmt: skip
    pytest.importorskip("torch")
    pytest.importorskip("stable_baselines3")
    from copi.envs.local_policy import LocalPolicyEnv
    from copi.errors import Interrupted
    from copi.rl import train

    drawn: list[str] = []
    plain = LocalPolicyEnv._draw

    def spy(self: LocalPolicyEnv) -> None:
        plain(self)
        drawn.append(self.sim.world.name)

    monkeypatch.setattr(LocalPolicyEnv, "_draw", spy)
    train(_config(), tmp_path / "whole.npz", validate_every=384, validation_episodes=1)
    kinds = [name.split("-")[0] for name in drawn]
    # the stages in order, none of a later stage before an earlier one's last episode
    first = {k: kinds.index(k) for k in ("star", "polygon", "crowd")}
    last = {k: len(kinds) - 1 - kinds[::-1].index(k) for k in ("star", "polygon", "crowd")}
    assert first["star"] == 0 and last["star"] < first["polygon"]
    assert last["polygon"] < first["crowd"] and kinds[-1] == "crowd"

    def stop(done: int, total: int) -> None:
        if done >= 900:  # in the last stage (crowd, from 768): the checkpoint of 768 is kept
            raise KeyboardInterrupt

    with pytest.raises(Interrupted):
        train(_config(), tmp_path / "cut.npz", checkpoints=tmp_path / "ck", validate_every=384,
              validation_episodes=1, progress=stop)  # fmt: skip
    saved = json.loads((tmp_path / "ck" / "last.json").read_text())["envs"]
    # the episodes under way were drawn in the stage before (the crowd's began at 768)
    assert {tuple(e["drawn_families"]) for e in saved} == {("polygon",)}
    resumed: list[int] = []
    train(_config(), tmp_path / "cut.npz", checkpoints=tmp_path / "ck", validate_every=384,
          validation_episodes=1, resumed=resumed.append)  # fmt: skip
    assert resumed == [768]
    assert _digest(tmp_path / "cut.npz") == _digest(tmp_path / "whole.npz")
