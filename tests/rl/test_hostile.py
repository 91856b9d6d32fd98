"""Hostile use of ``copi rl train``: Ctrl-C before the first checkpoint says what a rerun
does, a policy whose files would overwrite the checkpoint is refused before training, a
family whose sampler raises is named with its error, and a configuration of other kinds
than ints is refused in one line."""

from __future__ import annotations

import os
import re
import signal
import time
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from copi.errors import Interrupted, InvalidArgumentError
from tests.cli.test_faults import _one_line_error, run
from tests.rl.test_resume import _config


def _need_rl() -> None:
    pytest.importorskip("torch", reason="the optional extra rl")
    pytest.importorskip("stable_baselines3", reason="the optional extra rl")


def _stop(done: int, total: int) -> None:
    if done >= 100:
        raise KeyboardInterrupt


@pytest.mark.parametrize(("validate_every", "first"), [(500, 768), (10_000, 1536)])
def test_ctrl_c_before_the_first_checkpoint_says_a_rerun_starts_over(
    tmp_path: Path, validate_every: int, first: int
) -> None:
    """Rollouts of 3 x 128 steps: the first checkpoint is taken at the first rollout's end
    past ``validate_every``, or at the end of a run of 1,536 steps."""
    _need_rl()
    from copi.rl import train

    ck = tmp_path / "ck"
    with pytest.raises(Interrupted) as err:
        train(_config(), tmp_path / "p.npz", checkpoints=ck, validate_every=validate_every,
              validation_episodes=1, progress=_stop)  # fmt: skip
    assert str(err.value) == (
        f"nothing checkpointed yet in {ck} (the first checkpoint is taken after {first:,} "
        "steps); rerunning the same command starts over, and resumes from the checkpoints "
        "once there are some"
    )
    assert list(ck.iterdir()) == [] and not (tmp_path / "p.npz").exists()


def test_ctrl_c_while_a_checkpoint_is_written_leaves_it_whole(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A checkpoint is two files: a Ctrl-C between them waits until both are written."""
    _need_rl()
    import copi.rl._checkpoint as c
    import copi.rl._train as t

    write_text = c.write_text

    def interrupted(*args: Any, **kw: Any) -> Any:
        os.kill(os.getpid(), signal.SIGINT)  # after last.pt, before last.json
        time.sleep(0.05)  # the handler runs here, between two bytecodes
        return write_text(*args, **kw)

    monkeypatch.setattr(c, "write_text", interrupted)
    ck = tmp_path / "ck"
    with pytest.raises(Interrupted, match=f"^768 steps checkpointed in {re.escape(str(ck))};"):
        t.train(_config(), tmp_path / "p.npz", checkpoints=ck, validate_every=500,
                validation_episodes=1)  # fmt: skip
    saved = c._read_checkpoint(ck, _config())
    assert saved is not None and saved["meta"]["steps"] == 768
    # and the best validated policy so far (the first validation's), written whole
    assert sorted(p.name for p in ck.iterdir()) == ["best.npz", "last.json", "last.pt"]
    from copi.baselines import load_policy

    assert load_policy(ck / "best.npz").info["kept_steps"] == 768


def test_ctrl_c_without_checkpoints_says_how_to_keep_them(tmp_path: Path) -> None:
    _need_rl()
    from copi.rl import train

    with pytest.raises(Interrupted, match=r"^nothing saved \(give --checkpoints DIR"):
        train(_config(), tmp_path / "p.npz", validate_every=500, validation_episodes=1,
              progress=_stop)  # fmt: skip
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize(
    "output",
    [
        "rlc/last.npz",  # its learning curve, rlc/last.json, over the checkpoint's
        "rlc/sub/../last.npz",
        "link/last.npz",  # the checkpoints' directory by a symlink
    ],
)
def test_a_policy_over_the_checkpoint_is_refused_before_training(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch,
    output: str,
) -> None:  # fmt: skip
    monkeypatch.chdir(tmp_path)
    ck = tmp_path / "rlc"
    ck.mkdir()
    (tmp_path / "link").symlink_to(ck)
    (ck / "last.json").write_text('{"steps": 768}')
    (ck / "last.pt").write_bytes(b"weights")
    args = ["rl", "train", "-o", output, "--checkpoints", "rlc", "--steps", "300", "--envs", "1"]
    line = _one_line_error(*run(args, capsys)[::2])
    curve = Path(output).with_suffix(".json")
    assert line == (f"copi: error: {curve} would overwrite the checkpoint file last.json in "
                    "rlc; give the policy another name or another --checkpoints directory")
    assert (ck / "last.json").read_text() == '{"steps": 768}'
    assert (ck / "last.pt").read_bytes() == b"weights"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["link", "rlc"]
    assert sorted(p.name for p in ck.iterdir()) == ["last.json", "last.pt"]


def test_a_policy_beside_the_checkpoint_under_another_name_is_not_refused(
    tmp_path: Path,
) -> None:
    from copi.rl import check_apart

    check_apart(tmp_path / "rlc" / "policy.npz", tmp_path / "rlc")
    check_apart(tmp_path / "last.npz", tmp_path / "rlc")
    check_apart(tmp_path / "rlc" / "last.npz", None)
    with pytest.raises(InvalidArgumentError, match="would overwrite the checkpoint file last.pt"):
        check_apart(tmp_path / "rlc" / "last.pt", tmp_path / "rlc")


@pytest.fixture
def broken_family() -> Any:
    from copi.world import register_family, unregister_family

    def sampler(rng: np.random.Generator, *, name: str | None = None) -> Any:
        raise RuntimeError("the map server is down")

    register_family("fz-broken", sampler, summary="a family whose sampler raises")
    yield "fz-broken"
    unregister_family("fz-broken")


BROKEN = "the sampler of family 'fz-broken' raised RuntimeError: the map server is down"


def test_a_family_whose_sampler_raises_is_named_with_its_error(
    broken_family: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    _need_rl()
    out = tmp_path / "rf.npz"
    args = ["rl", "train", "-o", str(out), "--families", broken_family, "--steps", "300",
            "--envs", "1"]  # fmt: skip
    line = _one_line_error(*run(args, capsys)[::2])
    assert line == f"copi: error: {BROKEN}"
    assert list(tmp_path.iterdir()) == []


def test_validation_on_a_family_whose_sampler_raises_names_it(broken_family: str) -> None:
    from copi.baselines import Straight
    from copi.rl import TrainConfig, validation_success

    cfg = TrainConfig(families=(broken_family,))
    with pytest.raises(InvalidArgumentError, match=f"^{BROKEN}$"):
        validation_success(None, cfg, 2, agent=Straight())


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"steps": "x"}, "steps must be a positive int; got 'x'"),
        ({"steps": float("inf")}, "steps must be a positive int; got inf"),
        ({"steps": float("nan")}, "steps must be a positive int; got nan"),
        ({"envs": 2.0}, "envs must be a positive int; got 2.0"),
        ({"n_steps": True}, "n_steps must be a positive int; got True"),
        ({"max_steps": np.int64(500)}, "max_steps must be a positive int; got "),
        ({"n_epochs": -1}, "n_epochs must be a positive int; got -1"),
    ],
)
def test_a_configuration_of_other_kinds_is_refused_in_one_line(change: dict[str, Any],
                                                               message: str) -> None:  # fmt: skip
    with pytest.raises(InvalidArgumentError, match=f"^{re.escape(message)}") as err:
        _config(**change)
    assert "\n" not in str(err.value)

