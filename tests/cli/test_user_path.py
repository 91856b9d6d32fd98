"""What a new user meets first: a closed door, a map passed as a world file, a pipe closed
early. Each says what went wrong in one line, and nothing is counted that did not happen."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from copi.results import ResultsStore
from tests.cli.test_faults import ENV, _one_line_error, run

# a 20 x 10 room cut in two by a wall at x = 10, with a door of width `door` at y = 5
_ROOM = "[[0,0],[9.9,0],[9.9,{lo}],[10.1,{lo}],[10.1,0],[20,0],[20,10],[10.1,10],[10.1,{hi}],[9.9,{hi}],[9.9,10],[0,10]]"  # noqa: E501


def _room(tmp_path: Path, door: float) -> Path:
    lo, hi = 5 - door / 2, 5 + door / 2
    path = tmp_path / f"door-{door}.json"
    boundary = json.loads(_ROOM.format(lo=lo, hi=hi))
    path.write_text(json.dumps({"boundary": boundary, "start": [2, 5], "goal": [18, 5],
                                "name": f"door-{door}"}))  # fmt: skip
    return path


def test_a_door_narrower_than_the_agent_is_no_task_not_a_collision(tmp_path: Path, capsys) -> None:
    out = tmp_path / "closed.sqlite"
    code, text, err = run(["evaluate", "--method", "straight", "--world-file",
                           str(_room(tmp_path, 0.4)), "--worlds", "2", "-o", str(out)], capsys)  # fmt: skip
    assert code == 0, err
    assert "no episode ran, 2 skipped" in text
    assert "no way from the start (2, 5) to the goal (18, 5) for an agent of radius 0.3" in text
    with ResultsStore(out, readonly=True) as store:
        rows = store.episodes(store.runs()[0].run_id)
    assert [r["outcome"] for r in rows] == ["skipped", "skipped"]
    # a door the agent fits through is a task: the same command runs its episodes
    code, text, err = run(["evaluate", "--method", "compass-guard", "--world-file",
                           str(_room(tmp_path, 1.0)), "--worlds", "2", "-o",
                           str(tmp_path / "open.sqlite")], capsys)  # fmt: skip
    assert code == 0 and "2 episodes, success" in text and "skipped" not in text, text


def test_a_moving_ai_map_given_as_a_world_file_names_the_import(tmp_path: Path, capsys) -> None:
    m = tmp_path / "tiny.map"
    m.write_text("type octile\nheight 2\nwidth 2\nmap\n..\n..\n")
    code, _, err = run(["evaluate", "--method", "straight", "--world-file", str(m), "-o",
                        str(tmp_path / "r.sqlite")], capsys)  # fmt: skip
    line = _one_line_error(code, err)
    assert "not valid JSON" in line and f"copi world import-movingai {m} -o tiny.json" in line
    assert not (tmp_path / "r.sqlite").exists()


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="a POSIX pipe")
def test_a_reader_that_stops_early_is_no_error(learnt_caps: Path) -> None:
    """`copi inspect caps.npz --json | head -1`: the reader closes the pipe; copi stops
    quietly (no 'Broken pipe' error, no traceback)."""
    proc = subprocess.Popen([sys.executable, "-m", "copi.cli.main", "inspect", str(learnt_caps),
                             "--json"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=ENV,
                            bufsize=0)  # fmt: skip
    assert proc.stdout is not None and proc.stderr is not None
    first = proc.stdout.read(1)
    proc.stdout.close()  # as head does after its line
    err = proc.stderr.read().decode()
    proc.stderr.close()
    proc.wait(timeout=60)
    assert first == b"{"
    assert "Broken pipe" not in err and "Traceback" not in err and "error" not in err, err


def test_a_run_with_no_success_says_what_to_try(tmp_path: Path, capsys) -> None:
    # doors the agent fits through, but straight ignores the moving discs
    out = tmp_path / "none.sqlite"
    code, text, err = run(["evaluate", "--method", "straight", "--world-file",
                           str(_room(tmp_path, 2.0)), "--worlds", "3", "-o", str(out),
                           "--seed", "1"], capsys)  # fmt: skip
    assert code == 0, err
    assert "success 0.0 %, collision 100.0 %" in text  # (seed 1: every episode)
    assert "median excess — (no success)" in text and "nan" not in text
    assert "straight: no episode succeeded; most episodes ended in a collision: try" in err
    # a run that succeeds gets no such warning
    code, text, err = run(["evaluate", "--method", "compass-guard", "--world-file",
                           str(_room(tmp_path, 2.0)), "--worlds", "3", "-o",
                           str(tmp_path / "some.sqlite"), "--seed", "1"], capsys)  # fmt: skip
    assert code == 0 and "success 0.0 %" not in text and "no episode succeeded" not in err


def test_a_door_the_mapping_grid_would_close_is_warned_of(tmp_path: Path, capsys) -> None:
    """A door of 1.5 (2.5 agent diameters): open to the agent, but narrower than the
    distance under which the mapping strategy joins walls; a door of 2.2 is not."""
    from copi.online import Mapping
    from copi.world import load_worlds

    narrow, wide = _room(tmp_path, 1.5), _room(tmp_path, 2.2)
    assert Mapping().closes_the_way(load_worlds(narrow)[0], [2, 5], [18, 5], 0.3)
    assert not Mapping().closes_the_way(load_worlds(wide)[0], [2, 5], [18, 5], 0.3)
    args = ["evaluate", "--method", "compass-guard", "--sensing", "sensor", "--worlds", "1",
            "--sensor-strategy", "mapping", "--max-steps", "20"]  # fmt: skip
    code, _, err = run([*args, "--world-file", str(narrow), "-o", str(tmp_path / "n.sqlite")],
                       capsys)  # fmt: skip
    assert code == 0 and "world 'door-1.5': the occupancy grid of the mapping strategy" in err
    code, _, err = run([*args, "--world-file", str(wide), "-o", str(tmp_path / "w.sqlite")],
                       capsys)  # fmt: skip
    assert code == 0 and "occupancy grid" not in err
