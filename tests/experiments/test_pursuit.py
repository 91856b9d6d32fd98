from __future__ import annotations

from pathlib import Path

import pytest

from copi.experiments import PursuitConfig, ResultsStore, pursue, run_game, write_report
from copi.learning import LearnParams, learn


@pytest.fixture(scope="module")
def caps_path(tmp_path_factory: pytest.TempPathFactory) -> str:
    path = tmp_path_factory.mktemp("caps") / "caps.npz"
    learn(LearnParams(worlds=12, steps=200, seed=1, directions=8)).save(path)
    return str(path)


def test_games_depend_on_their_index_only(caps_path: str) -> None:
    cfg = PursuitConfig(caps_path, games=3, horizon=120).resolved()
    a, b = run_game(cfg, 2), run_game(cfg, 2)
    assert a == b
    assert a.survival == (a.capture_time if a.captured else 120)


def test_the_game_evader_meets_obstacles_the_capability_evader_avoids(caps_path: str) -> None:
    game = PursuitConfig(caps_path, evader="game", games=12, horizon=150).resolved()
    capa = PursuitConfig(caps_path, evader="capability", games=12, horizon=150).resolved()
    touched_game = sum(run_game(game, k).contacts for k in range(12))
    touched_capa = sum(run_game(capa, k).contacts for k in range(12))
    assert touched_capa <= touched_game


def test_runner_store_and_fig5(caps_path: str, tmp_path: Path) -> None:
    out = tmp_path / "games.sqlite"
    for dynamic in (False, True):
        pursue(PursuitConfig(caps_path, games=4, horizon=100, dynamic=dynamic), out, workers=2)
    one = tmp_path / "one.sqlite"
    pursue(PursuitConfig(caps_path, games=4, horizon=100, dynamic=True), one)
    with ResultsStore(out) as a, ResultsStore(one) as b:
        rows_a = [r for r in a.games() if r["method"] == "capability-dynamic"]
        rows_b = b.games()
        assert [{k: v for k, v in r.items()} for r in rows_a] == rows_b
    report = write_report([out], tmp_path / "rep")
    text = report.read_text()
    assert "Experiment 2" in text and "capability-static" in text
    assert (tmp_path / "rep" / "fig5_pursuit.png").exists()
