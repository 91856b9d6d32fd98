"""Capabilities taken to a Moving AI map (issue: a newcomer's first hour): the map is
scaled for disc agents, and the learnt agent gets somewhere and says how it fared."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.cli.test_main import run
from tests.common import MAPS

ROOM = MAPS / "mapf" / "room-32-32-4.map"


def test_a_moving_ai_map_scaled_for_disc_agents(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    import json

    room = tmp_path / "room.json"
    code, out, err = run(
        ["world", "import-movingai", str(ROOM), "-o", str(room), "--passage", "3"], capsys
    )
    assert code == 0, err
    world = json.loads(room.read_text())
    world = world[0] if isinstance(world, list) else world
    # one-cell doors are 3 steps wide now, and the moving obstacles fit them
    assert world["obstacles"]["radius"][1] <= 0.3 * 3 + 1e-9
    code, out, err = run(
        ["evaluate", "-o", str(tmp_path / "r.sqlite"), "--method", "compass-guard",
         "--world-file", str(room), "--worlds", "6", "--max-steps", "300"],
        capsys,
    )  # fmt: skip
    assert code == 0, err
    assert float(out.split("success ")[1].split(" %")[0]) > 0, out
    assert "standing still 0.0 %" in out
    code, _, err = run(
        ["world", "import-movingai", str(ROOM), "-o", str(tmp_path / "x.json"), "--passage",
         "3", "--near", "1", "1"],
        capsys,
    )  # fmt: skip
    assert code == 2 and "--near and --passage do not go together" in err


def test_a_run_that_mostly_stands_still_says_so(tmp_path: Path) -> None:
    from copi.reports import warnings_for

    assert warnings_for("m", {"no_policy": 0.77, "unfamiliar": 0.0})[0].startswith(
        "m commanded no motion in 77 % of steps"
    )
    assert warnings_for("m", {"no_policy": 0.1, "unfamiliar": 0.6})[0].startswith(
        "m saw unfamiliar readings in 60 % of steps"
    )
    assert warnings_for("m", {"no_policy": 0.1, "unfamiliar": 0.1}) == []
