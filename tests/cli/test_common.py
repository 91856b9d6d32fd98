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


def test_a_resumed_run_counts_its_rate_from_where_it_resumed(
    capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """600 of 1000 done before: 10 done in 2 s is 5/s and 78 s to go, not 305/s."""
    clock = iter([0.0] * 4 + [2.0] * 4)
    monkeypatch.setattr(_common.time, "monotonic", lambda: next(clock))
    with PlainProgress(every=0.0) as bar:
        task = bar.add_task("episodes", total=1000)
        bar.update(task, completed=600, resumed=True)
        bar.update(task, completed=610)
    lines = capsys.readouterr().err.strip().splitlines()
    assert lines[0] == "episodes: 600/1000 (60 %), elapsed 0s", lines
    assert lines[1] == "episodes: 610/1000 (61 %), 5.0/s, ETA 1m18s, elapsed 2s", lines


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
    _common.compiling_notice(["copi.geometry.kernels:step_world"])
    # the test session has run the simulator, so its kernel is cached by now or being
    # compiled in this process; a name that is not a kernel is taken as cached too
    _common.compiling_notice(["copi.geometry.kernels:no_such_kernel"])
    err = capsys.readouterr().err
    assert err == "" or err.startswith("compiling kernels once (numba), ~4 s")

    class Uncached:
        class _cache:  # noqa: N801 - mimics numba's dispatcher
            class _cache_file:  # noqa: N801
                @staticmethod
                def _load_index() -> dict:
                    return {}

    monkeypatch.setattr(_common, "_noticed", False)
    monkeypatch.setattr("copi.online.kernels.decide", Uncached, raising=True)
    _common.compiling_notice(["copi.online.kernels:decide"])
    _common.compiling_notice(["copi.online.kernels:decide"])  # once per process
    err = capsys.readouterr().err
    assert err.splitlines() == ["compiling kernels once (numba), ~2 s; later runs reuse them"]


def _run(args: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str, str]:
    with pytest.raises(SystemExit) as exit_:
        main(args)
    captured = capsys.readouterr()
    return int(exit_.value.code or 0), captured.out, captured.err


def test_version_and_help_text(capsys: pytest.CaptureFixture[str]) -> None:
    import copi

    code, out, _ = _run(["--version"], capsys)
    assert code == 0 and out.strip() == f"copi {copi.__version__}"
    _, out, _ = _run(["world", "sample", "--help"], capsys)
    assert "default_rng([seed, k])" in out
    _, out, _ = _run(["world", "show", "--help"], capsys)
    assert "--gif" in out and "<bool>" not in out
    _, out, _ = _run(["world", "import-movingai", "--help"], capsys)
    assert "row y counted" in " ".join(out.replace("│", " ").split())


def test_plan_summarises_long_paths(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    from tests.common import U_TRAP

    worlds = tmp_path / "u.json"
    save_worlds([U_TRAP], worlds)
    # from below the U round its corners to the goal above it: a path of many vertices
    args = ["plan", str(worlds), "--start", "20", "2", "--goal", "20", "28", "--radius", "0.5"]
    code, out, _ = _run(args, capsys)
    lines = out.strip().splitlines()
    n = int(lines[0].split("(")[1].split()[0]) + 1
    assert n > 7 and len(lines) == 1 + 7 and f"{n - 6} more vertices" in out
    code, out, _ = _run([*args, "--vertices"], capsys)
    assert code == 0 and len(out.strip().splitlines()) == 1 + n
