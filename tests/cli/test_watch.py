from __future__ import annotations

from pathlib import Path

import pytest
from PIL import Image

from copi.cli import main


def run(args: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str, str]:
    with pytest.raises(SystemExit) as exit_:
        main(args)
    captured = capsys.readouterr()
    return int(exit_.value.code or 0), captured.out, captured.err


def test_watch_writes_a_gif_with_the_episodes_frames(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    gif = tmp_path / "sub" / "ep.gif"
    code, out, err = run(
        ["watch", "--method", "dwa", "--episode", "2", "--max-steps", "25", "--size", "160",
         "-o", str(gif)],
        capsys,
    )  # fmt: skip
    assert code == 0, err
    steps = int(out.split(" after ")[1].split()[0])
    with Image.open(gif) as im:
        assert im.n_frames == steps + 1
    assert f"{steps + 1} frame(s)" in out and "dwa (map) in star-00002" in out


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["watch", "-o", "x.gif"], "give a capabilities file (for copi's modes), --preset NAME or --method NAME"),
        (["watch", "--method", "copi-extended", "-o", "x.gif"],
         "copi-extended needs a capabilities file"),
        (["watch", "--method", "dwa", "-o", "x.avi"], "-o must end in .gif, .mp4, .png"),
        (["watch", "--method", "astar", "-o", "x.gif"], "method must be one of"),
        (["watch", "--method", "dwa", "--family", "moon", "-o", "x.gif"], "family must be one of"),
        (["watch", "--method", "replan", "--sensing", "map", "-o", "x.gif"],
         "replan needs sensing level 'oracle'"),
        (["watch", "nope.npz", "-o", "x.gif"], "nope.npz"),
        (["watch", "--method", "dwa", "--world-file", "nope.json", "-o", "x.gif"],
         "nope.json: no such world file"),
    ],
)  # fmt: skip
def test_bad_inputs_exit_2_with_one_line(
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
    args: list[str],
    message: str,
) -> None:
    monkeypatch.chdir(tmp_path)
    code, _, err = run(args, capsys)
    assert code == 2 and message in err and "Traceback" not in err, err
    assert len(err.strip().splitlines()) == 1, err
    assert not (tmp_path / "x.gif").exists()
