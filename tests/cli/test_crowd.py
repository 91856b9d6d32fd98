"""``copi crowd``: a run writes its store, figure and animation; bad input is one line,
exit code 2, and nothing written."""

from __future__ import annotations

from pathlib import Path

import pytest
from PIL import Image

from copi.results import ResultsStore
from tests.cli.test_faults import _one_line_error, run


def test_a_crowd_writes_its_rows_figure_and_animation(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "c"
    code, text, err = run(["crowd", "--agents", "40", "--method", "compass-guard,straight",
                           "--steps", "12", "--density", "0.05,0.2", "-o", str(out)], capsys)  # fmt: skip
    assert code == 0, err
    with ResultsStore(out / "crowd.sqlite", readonly=True) as store:
        rows = store.lifelong()
        runs = [r for r in store.runs() if r.experiment == "crowd"]
    assert len(rows) == 2 * 2 * 40 and len(runs) == 4
    assert {r.outcome for r in rows} <= {"success", "collision", "timeout"}
    assert "compass-guard (sensor), 40 agents at density 0.05, 1 run(s): success" in text
    with Image.open(out / "crowd.png") as png:
        assert png.size[0] > 400
    with Image.open(out / "crowd.gif") as gif:
        assert gif.n_frames == 13 and gif.size == (480, 480)
    # the same command again: everything is stored, nothing runs twice
    code, again, err = run(["crowd", "--agents", "40", "--method", "compass-guard,straight",
                            "--steps", "12", "--density", "0.05,0.2", "-o", str(out)], capsys)  # fmt: skip
    assert code == 0, err
    with ResultsStore(out / "crowd.sqlite", readonly=True) as store:
        assert len(store.lifelong()) == len(rows)


def test_copi_learnt_runs_on_a_given_capabilities_file(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], learnt_caps: Path
) -> None:
    out = tmp_path / "c"
    code, text, err = run(["crowd", str(learnt_caps), "--agents", "30", "--steps", "8",
                           "--no-gif", "-o", str(out)], capsys)  # fmt: skip
    assert code == 0, err
    assert "copi-learnt (sensor), 30 agents at density 0.1" in text
    assert not (out / "crowd.gif").exists() and not list(out.glob("capabilities-*"))


@pytest.mark.parametrize(
    ("args", "says"),
    [
        (["--method", "nosuch"], "method must be one of"),
        (["--method", ""], "empty"),
        (["--agents", "-5"], "agents must be a positive int; got -5"),
        (["--agents", "1000000"], "agents must be at most 100,000"),
        (["--steps", "0"], "steps must be a positive int; got 0"),
        (["--runs", "-1"], "runs must be a positive int; got -1"),
        (["--steps", "200000"], "steps must be at most 100,000"),
        (["--runs", "5000"], "runs must be at most 1,000"),
        (["--density", "9"], "density must be at most 2.7 agents per square agent step"),
        (["--density", "-0.1"], "density must be a finite number > 0"),
        (["--density", "abc"], "--density takes numbers"),
        (["--agents", "400", "--density", "2.2"], "cannot place 400 agents of radius 0.3 without overlap"),
        (["--method", "clairvoyant"], "the future of every moving body"),
        (["--sensing", "future"], "sensing must be sensor, map or oracle"),
        (["--size", "4096", "--steps", "5000"], "frames would hold"),
    ],
)
def test_bad_input_is_one_line_and_writes_nothing(
    args: list[str], says: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "out"
    base = ["crowd", "--method", "compass-guard", "--steps", "5", "-o", str(out)]
    code, _, err = run([*base, *args], capsys)
    line = _one_line_error(code, err)
    assert says in line, line
    assert not out.exists()


def test_a_capabilities_file_for_methods_that_need_none_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], learnt_caps: Path
) -> None:
    code, _, err = run(["crowd", str(learnt_caps), "--method", "compass-guard", "-o",
                        str(tmp_path / "o")], capsys)  # fmt: skip
    assert "run(s) on no capabilities" in _one_line_error(code, err)
    code, _, err = run(["crowd", str(tmp_path / "missing.npz"), "-o", str(tmp_path / "o")], capsys)
    assert "missing.npz" in _one_line_error(code, err)
    assert not (tmp_path / "o").exists()
