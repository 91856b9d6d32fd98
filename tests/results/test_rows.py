"""One row type per table, the same written and read back."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

from copi.results import EpisodeRow, GameRow, LifeRow, ResultsStore
from copi.results._rows import columns


def test_a_row_written_reads_back_as_the_same_type_with_its_run(tmp_path: Path) -> None:
    row = EpisodeRow(
        episode=3, world="w", seed=0, success=False, reached=False, collided=True,
        timed_out=False, steps=7, contacts=1, path_length=6.5, optimal_length=9.0,
        excess=math.nan, decision_us=2.0, strategy_us=0.0, unfamiliar=0.25, no_policy=0,
        outcome="collision", trajectory={"path": [[0, 0], [1, 1]]},
    )  # fmt: skip
    game = GameRow(game=1, world="w", seed=0, dynamic=True, captured=True, capture_time=12.0,
                   survival=12.0, contacts=0, closest=0.4, gamma=0.7, beta=0.2,
                   outcome="captured")  # fmt: skip
    life = LifeRow(world="w", life=0, task=2, seed=0, family="indoor", sensing="sensor",
                   outcome="success", success=True, steps=30, path_length=28.0,
                   optimal_length=25.0, excess=0.12, decision_us=3.0, unfamiliar=0.0, grown=2,
                   options=5, strategy="causal")  # fmt: skip
    with ResultsStore(tmp_path / "r.sqlite") as store:
        store.begin("r", "navigation", "m", {})
        store.add("r", "navigation", "m", row)
        store.add_game("r", "pursuit", "m", game)
        store.add_life("r", "lifelong", "m", [life])
        back, = store.episodes()
        back_game, = store.games()
        back_life, = store.lifelong()
    assert type(back) is EpisodeRow and (back.run_id, back.method) == ("r", "m")
    assert back.excess is None and back.trajectory is None  # NaN reads as NULL
    nulls = {k: None for k in ("excess", "time_to_goal", "min_clearance", "smoothness")}
    assert back == dataclasses.replace(row, run_id="r", experiment="navigation", method="m",
                                       trajectory=None, **nulls)  # fmt: skip
    assert back_game == dataclasses.replace(game, run_id="r", experiment="pursuit", method="m")
    assert back_life == dataclasses.replace(life, run_id="r", experiment="lifelong", method="m")
    assert "trajectory" not in back.keys() and back.keys()[:3] == ["run_id", "experiment",
                                                                  "method"]  # fmt: skip
    assert columns(EpisodeRow, identity=False)[0] == "episode"
