from __future__ import annotations

from pathlib import Path

import pytest

from copi.experiments import PursuitConfig, pursue, run_game
from copi.learning import LearnParams, learn
from copi.reports import write_report
from copi.results import ResultsStore


@pytest.fixture(scope="module")
def caps_path(tmp_path_factory: pytest.TempPathFactory) -> str:
    path = tmp_path_factory.mktemp("caps") / "caps.npz"
    learn(LearnParams(worlds=12, steps=200, seed=1, directions=8)).save(path)
    return str(path)


def test_games_depend_on_their_index_only(caps_path: str) -> None:
    cfg = PursuitConfig(caps_path, games=3, horizon=120).resolved()
    a = run_game(cfg, 2)
    others = [run_game(cfg, k) for k in (0, 1)]  # games played in between change nothing
    assert run_game(cfg, 2) == a
    assert all(o.world != a.world for o in others)  # each index its own world
    # survival is the capture time, the contact's time, or the whole horizon
    rows = [a, *others]
    for r in rows:
        assert r.outcome in ("captured", "collision", "escaped")
        if r.outcome == "captured":
            assert r.captured and r.survival == r.capture_time < 120
        elif r.outcome == "collision":
            assert r.contacts >= 1 and r.survival < 120
        else:
            assert not r.captured and r.contacts == 0 and r.survival == 120.0


def test_a_contact_ends_the_game_as_a_loss_and_the_rows_differ(caps_path: str) -> None:
    n = 16
    static = PursuitConfig(caps_path, evader="game", dynamic=False, games=n, horizon=150)
    dynamic = PursuitConfig(caps_path, evader="game", dynamic=True, games=n, horizon=150)
    old = PursuitConfig(caps_path, evader="game", dynamic=True, games=n, horizon=150,
                        contact_ends=False)  # fmt: skip
    rows = {
        name: [run_game(cfg.resolved(), k) for k in range(n)]
        for name, cfg in (("static", static), ("dynamic", dynamic), ("old", old))
    }
    for r in rows["static"]:
        assert r.contacts == 0 and r.outcome != "collision"
    collided = [r for r in rows["dynamic"] if r.outcome == "collision"]
    assert collided, "the game evader ignores the discs: some games must end in a contact"
    for r in collided:
        assert r.contacts == 1 and not r.captured and r.survival < 150
    for r in rows["dynamic"]:
        assert r.outcome == ("captured" if r.captured else "collision" if r.contacts else
                             "escaped")  # fmt: skip
    # The older rule lets the game go on: the same games reach capture or the horizon.
    for new, was in zip(rows["dynamic"], rows["old"], strict=True):
        if new.outcome == "collision":
            assert was.contacts >= 1 and was.survival >= new.survival
    # So the stationary and dynamic rows now differ in what they report, not only in
    # their contact counts.
    outcome = {name: [r.outcome for r in rs] for name, rs in rows.items()}
    assert outcome["static"] != outcome["dynamic"]


def test_the_game_evader_meets_obstacles_the_capability_evader_avoids(caps_path: str) -> None:
    game = PursuitConfig(caps_path, evader="game", games=12, horizon=150).resolved()
    capa = PursuitConfig(caps_path, evader="capability", games=12, horizon=150).resolved()
    touched_game = sum(run_game(game, k).contacts for k in range(12))
    touched_capa = sum(run_game(capa, k).contacts for k in range(12))
    assert touched_capa <= touched_game


def test_the_learnt_evader_plays_the_game_through_the_learnt_preset(tmp_path: Path) -> None:
    learnt = tmp_path / "learnt.npz"
    learn(LearnParams(worlds=6, steps=150, directions=16, safety=True, probe_worlds=6,
                      probe_steps=60, seed=1)).save(learnt)  # fmt: skip
    cfg = PursuitConfig(str(learnt), evader="learnt", guard=1.05, games=8, horizon=150)
    cfg = cfg.resolved()
    assert cfg.method == "learnt-dynamic"
    rows = [run_game(cfg, k) for k in range(8)]
    assert rows[3] == run_game(cfg, 3)  # a game depends on its index only
    game = PursuitConfig(str(learnt), evader="game", games=8, horizon=150).resolved()
    touched_game = sum(run_game(game, k).contacts for k in range(8))
    assert sum(r.contacts for r in rows) <= touched_game
    # The learnt evader survives at least as long as the bare game's velocity, in total.
    assert sum(r.survival for r in rows) >= sum(run_game(game, k).survival for k in range(8))


def test_runner_store_and_fig5(caps_path: str, tmp_path: Path) -> None:
    out = tmp_path / "games.sqlite"
    for dynamic in (False, True):
        pursue(PursuitConfig(caps_path, games=4, horizon=100, dynamic=dynamic), out, workers=2)
    one = tmp_path / "one.sqlite"
    pursue(PursuitConfig(caps_path, games=4, horizon=100, dynamic=True), one)
    with ResultsStore(out) as a, ResultsStore(one) as b:
        rows_a = [r for r in a.games() if r["method"] == "capability-dynamic"]
        rows_b = b.games()
        assert rows_a == rows_b
    report = write_report([out], tmp_path / "rep")
    text = report.path.read_text()
    assert "Experiment 2" in text and "capability-static" in text
    provenance = [ln for ln in text.splitlines() if ln.startswith("- **capability-")]
    assert len(provenance) == 2 and all("4 games, seed 0, evader capability" in ln
                                        for ln in provenance)  # fmt: skip
    assert "stationary obstacles, horizon 100, guard 1.2" in provenance[0]
    assert (tmp_path / "rep" / "fig5_pursuit.png").exists()


def test_a_policy_registered_without_a_guard_plays_the_game_without_one() -> None:
    """The game hands its guard to the evaders registered with one (ppo-guard, compass-
    guard); a PPO policy registered with none (ppo-chauffeur, ppo) plays as trained, not
    shielded (it once was: its survival was the guard's)."""
    from copi.experiments.pursuit import _evader_agent
    from copi.methods import method_spec
    from copi.world import RangeSensor

    sensor = RangeSensor()
    for name, guard in (("ppo-chauffeur", 0.0), ("ppo", 0.0), ("ppo-guard", 1.2),
                        ("compass-guard", 1.2)):  # fmt: skip
        if not method_spec(name).available():
            continue
        agent = _evader_agent(None, PursuitConfig(None, evader=name, guard=1.2), sensor)
        assert agent.guard == guard, name  # type: ignore[attr-defined]
