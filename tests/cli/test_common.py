from __future__ import annotations

import re
from pathlib import Path

import pytest

from copi.cli import _common, main
from copi.cli._common import PlainProgress
from copi.world import random_world, save_worlds


def test_plain_progress_prints_done_rate_and_eta(capsys: pytest.CaptureFixture[str]) -> None:
    with PlainProgress(every=0.0) as bar:
        task = bar.add_task("episodes", total=4)
        for k in range(1, 4):
            bar.update(task, completed=k)
        bar.advance(task)
        bar.advance(task, 0)  # already said: no second final line
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 4, lines
    assert lines[0].startswith("episodes: 1/4 (25 %), ") and "ETA" in lines[0]
    assert re.search(r"/s|s each", lines[0])
    assert lines[-1].startswith("episodes: 4/4 (100 %), ") and "ETA" not in lines[-1]


def test_a_non_tty_run_prints_progress_lines(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    worlds = tmp_path / "w.json"
    save_worlds([random_world(0, name="a"), random_world(1, name="b")], worlds)
    monkeypatch.setenv("COPI_PROGRESS_EVERY", "0")
    with pytest.raises(SystemExit) as exit_:
        main(["world", "show", str(worlds), "-o", str(tmp_path / "pics"), "--steps", "5"])
    assert exit_.value.code in (0, None)
    err = capsys.readouterr().err
    assert "random walks: 1/2 (50 %)" in err and "random walks: 2/2 (100 %)" in err
    assert "pictures: 2/2 (100 %)" in err


def test_compiling_notice_only_when_a_kernel_is_not_cached(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.setattr(_common, "_noticed", False)
    _common.compiling_notice(["copi.geometry._kernels:step_world"])
    # the test session has run the simulator, so its kernel is cached by now or being
    # compiled in this process; a name that is not a kernel is taken as cached too
    _common.compiling_notice(["copi.geometry._kernels:no_such_kernel"])
    err = capsys.readouterr().err
    assert err == "" or err.startswith("compiling kernels once (numba), ~4 s")

    class Uncached:
        class _cache:  # noqa: N801 - mimics numba's dispatcher
            class _cache_file:  # noqa: N801
                @staticmethod
                def _load_index() -> dict:
                    return {}

    monkeypatch.setattr(_common, "_noticed", False)
    monkeypatch.setattr("copi.online._kernels.decide", Uncached, raising=True)
    _common.compiling_notice(["copi.online._kernels:decide"])
    _common.compiling_notice(["copi.online._kernels:decide"])  # once per process
    err = capsys.readouterr().err
    assert err.splitlines() == ["compiling kernels once (numba), ~2 s; later runs reuse them"]
