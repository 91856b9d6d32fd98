"""Experiment 3: lives of successive tasks, what the agent is told, what it keeps,
the runner and its store, the report, and bad input at the CLI."""

from __future__ import annotations

import sqlite3
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from copi.core import Agent, Observation, Task
from copi.experiments.lifelong import (
    LifelongConfig,
    draw_life,
    parse_lifelong_methods,
    run_lifelong,
    world_identity,
)
from copi.learning import Capabilities, LearnParams, learn
from copi.methods import MethodRun, make_agent
from copi.online import CausalMap, CausalMapFormatError, LearntAgent
from copi.reports import lifelong_blocks
from copi.results import ResultsStore, lives_difference
from copi.runs import run_episode
from tests.cli.test_main import run


@pytest.fixture(scope="module")
def learnt(tmp_path_factory: pytest.TempPathFactory) -> str:
    path = tmp_path_factory.mktemp("caps") / "capabilities-learnt.npz"
    learn(LearnParams(worlds=6, steps=150, directions=16, safety=True, probe_worlds=6,
                      probe_steps=60, seed=1)).save(path)  # fmt: skip
    return str(path)


def test_a_life_is_a_chain_of_tasks_drawn_from_its_index() -> None:
    sims = draw_life("indoor", 3, 0, 4)
    again = draw_life("indoor", 3, 0, 4)
    for a, b in zip(sims, again, strict=True):
        assert np.array_equal(a.position, b.position) and np.array_equal(a.goal, b.goal)
        assert np.array_equal(a.centers, b.centers)
    for before, after in zip(sims, sims[1:], strict=False):
        assert np.array_equal(after.position, before.goal)  # a task starts at the last goal
        assert np.hypot(*(after.goal - after.position)) >= 10.0
    assert len({s.world.name for s in sims}) == 1
    assert sims[0].world.name == world_identity("indoor", 3, 0)
    other = draw_life("indoor", 4, 0, 1)[0]
    assert not np.array_equal(other.goal, sims[0].goal)


class _Spy(Agent):
    name = "spy"
    sensing = "sensor"

    def __init__(self) -> None:
        self.tasks: list[Task] = []
        self.seen: list[Observation] = []
        self.outcomes: list[str] = []

    def reset(self, task: Task) -> None:
        self.tasks.append(task)

    def act(self, obs: Observation) -> Any:
        self.seen.append(obs)
        return np.array([1.0, 0.0])

    def finish(self, outcome: str) -> None:
        self.outcomes.append(outcome)


def test_a_lifelong_agent_is_told_its_odometry_and_nothing_more() -> None:
    sims = draw_life("indoor", 0, 0, 2)
    origin = sims[0].position.copy()
    spy = _Spy()
    for sim in sims:
        start = sim.position.copy()
        out = run_episode(spy, sim, sensing="sensor", max_steps=5, origin=origin)
        first = spy.seen[-out.steps]
        assert np.allclose(first.odometry, start - origin)
        assert first.position is None and first.static is None and first.obstacles is None
    assert [t.lifelong for t in spy.tasks] == [True, True]
    assert all(t.world is None for t in spy.tasks)
    assert len(spy.outcomes) == 2  # told how each task ended
    # Outside a life there is no odometry.
    single = _Spy()
    run_episode(single, draw_life("indoor", 0, 0, 1)[0], sensing="sensor", max_steps=2)
    assert single.seen[0].odometry is None and not single.tasks[0].lifelong


def test_continual_contexts_grow_and_make_a_reading_familiar(learnt: str) -> None:
    caps = Capabilities.load(learnt)
    agent = make_agent("copi-learnt", caps, continual=True)
    assert isinstance(agent, LearntAgent)
    sim = draw_life("indoor", 0, 0, 1)[0]
    run_episode(agent, sim, sensing="sensor", max_steps=3, origin=sim.position.copy())
    odd = np.full(caps.n_rays, 0.4)  # a reading no exploration produced: walls all round
    odd[::2] = 9.5
    obs = Observation(ranges=odd, goal=np.array([5.0, 0.0]), odometry=np.zeros(2))
    for _ in range(40):
        agent.act(obs)
    assert agent.n_learnt > 0
    before = agent.n_unfamiliar
    agent.act(obs)
    assert agent.n_unfamiliar == before  # now familiar: a grown node sits near it
    fixed = make_agent("copi-learnt", caps)
    fixed.reset(Task("sensor", 0.3, 0.5, caps.n_rays, 10.0))
    for _ in range(3):
        fixed.act(obs)
    assert fixed.n_unfamiliar == 3 and fixed.n_learnt == 0  # without growth it stays odd


def _rows(path: Path) -> list[dict]:
    with ResultsStore(path, readonly=True) as store:
        return [{k: v for k, v in r.items() if k != "decision_us"} for r in store.lifelong()]


def test_runner_resumes_a_life_at_a_time_and_saves_causal_maps(learnt: str, tmp_path: Path) -> None:
    methods = ("copi-learnt@sensor:causal", "compass-guard@sensor:mapping")
    cfg = LifelongConfig(learnt, family="indoor", worlds=2, tasks=3, methods=methods,
                         maps=str(tmp_path / "maps"))  # fmt: skip
    out = tmp_path / "life.sqlite"
    runs = run_lifelong(cfg, out, workers=1)
    rows = _rows(out)
    assert len(rows) == 2 * 2 * 3 and {r.label for r in runs} == set(methods)
    by_task: dict[tuple[int, int], list[dict]] = {}
    for r in rows:
        by_task.setdefault((r["life"], r["task"]), []).append(r)
        assert r["outcome"] in ("success", "collision", "timeout")
        assert r["success"] == (r["outcome"] == "success")
    for group in by_task.values():  # the same task for every method
        assert len({g["optimal_length"] for g in group}) == 1
    causal = [r for r in rows if r["method"] == "copi-learnt" and r["strategy"] == "causal"]
    for life in (0, 1):
        opts = [r["options"] for r in causal if r["life"] == life]
        assert opts == sorted(opts) and opts[-1] > 0  # the map only grows through a life
    # A lost life is run again, whole; the others are not touched.
    with sqlite3.connect(out) as db:
        db.execute("DELETE FROM lifelong WHERE life = 1 AND method = 'compass-guard'")
    run_lifelong(cfg, out, workers=2)
    assert _rows(out) == rows
    # Each causal life was saved, for its world and these capabilities.
    from copi._files import file_sha

    ident = world_identity("indoor", 0, 0)
    saved = tmp_path / "maps" / f"copi-learnt-sensor-causal-{ident}.npz"
    cmap, occ = CausalMap.load(saved, world=ident, capabilities=file_sha(learnt))
    assert cmap.n_options == causal[2]["options"] and occ is not None
    with pytest.raises(CausalMapFormatError, match="a causal map of world"):
        CausalMap.load(saved, world=world_identity("indoor", 1, 0))


def test_lives_difference_against_a_hand_computed_case() -> None:
    def life(outcomes: list[str], excess: list[float]) -> list[dict]:
        return [{"task": t, "outcome": o, "excess": e}
                for t, (o, e) in enumerate(zip(outcomes, excess, strict=True))]  # fmt: skip

    a = {0: life(["success", "success"], [0.1, 0.2]), 1: life(["success", "timeout"], [0.3, 0])}
    b = {0: life(["success", "timeout"], [0.2, 0.0]), 1: life(["success", "timeout"], [0.5, 0])}
    s = lives_difference(a, b, "success")
    assert s.estimate == pytest.approx(3 / 4 - 2 / 4) and s.n == 4
    e = lives_difference(a, b, "excess")  # tasks both succeeded in: (0.1 vs 0.2), (0.3 vs 0.5)
    assert e.estimate == pytest.approx(np.median([0.1, 0.3]) - np.median([0.2, 0.5])) and e.n == 2
    assert e.low <= e.estimate <= e.high
    assert lifelong_blocks(50) == (range(0, 10), range(40, 50))
    assert lifelong_blocks(10) == (range(0, 2), range(8, 10))


def test_the_cli_runs_and_reports(learnt: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "run.sqlite"
    code, text, err = run(["lifelong", learnt, "-o", str(out), "--worlds", "1", "--tasks", "2",
                           "--methods", "copi-learnt@sensor:causal,dwa@sensor:mapping", "--workers", "1"],
                          capsys)  # fmt: skip
    assert code == 0, err
    assert "| **copi-learnt@sensor:causal** | sensor | causal | causal map + grid |" in text
    assert "| dwa@sensor:mapping | sensor | mapping | grid |" in text and "Goals:" in text
    assert out.with_suffix(".png").stat().st_size > 10_000


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--methods", "astar"], "method must be one of copi-faithful"),
        (["--family", "moon"], "family must be one of"),
        (["--tasks", "0"], "--tasks"),
    ],
)
def test_bad_input_is_one_line_and_writes_nothing(
    args: list[str], message: str, learnt: str, tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:  # fmt: skip
    out = tmp_path / "run.sqlite"
    code, _, err = run(["lifelong", learnt, "-o", str(out), *args], capsys)
    assert code == 2 and message in err and "Traceback" not in err, err
    assert not out.exists()


def test_capabilities_without_priors_are_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    plain = tmp_path / "plain.npz"
    learn(LearnParams(worlds=3, steps=60, directions=16, seed=0)).save(plain)
    out = tmp_path / "run.sqlite"
    code, _, err = run(["lifelong", str(plain), "-o", str(out), "--worlds", "1"], capsys)
    assert code == 2 and (
        "was learnt for preset extended (16 directions, no safety priors); preset learnt "
        "needs 16 directions, safety priors: learn it with copi learn --preset learnt"
    ) in err, err
    assert "Traceback" not in err
    assert not out.exists()
    assert parse_lifelong_methods("dwa, dwa@sensor:mapping") == (
        MethodRun("dwa", "sensor", "mapping"),
    )
    assert parse_lifelong_methods("copi-learnt")[0].strategy == "causal"


def test_a_life_resumes_from_saved_maps_and_bad_maps_are_refused(
    learnt: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    maps = tmp_path / "maps"
    base = ["lifelong", learnt, "--worlds", "1", "--tasks", "2", "--methods",
            "copi-learnt@sensor:causal", "--workers", "1"]  # fmt: skip
    code, _, err = run([*base, "-o", str(tmp_path / "a.sqlite"), "--maps", str(maps)], capsys)
    assert code == 0, err
    code, _, err = run([*base, "-o", str(tmp_path / "b.sqlite"), "--from-maps", str(maps)],
                       capsys)  # fmt: skip
    assert code == 0, err
    a, b = _rows(tmp_path / "a.sqlite"), _rows(tmp_path / "b.sqlite")
    # The resumed life starts with the first life's options and adds its own.
    assert b[0]["options"] > a[-1]["options"]
    saved = maps / f"copi-learnt-sensor-causal-{world_identity('indoor', 0, 0)}.npz"
    # A map of another world (the file renamed), truncated, or missing: one line, exit 2.
    other = tmp_path / "other"
    other.mkdir()
    (other / saved.name.replace("0000", "0001")).write_bytes(saved.read_bytes())
    code, _, err = run([*base, "--worlds", "2", "-o", str(tmp_path / "c.sqlite"),
                        "--from-maps", str(other)], capsys)  # fmt: skip
    assert code == 2 and "no causal map of copi-learnt@sensor:causal in world indoor-life-0000" in err
    (other / saved.name).write_bytes(saved.read_bytes())
    code, _, err = run([*base, "--worlds", "2", "-o", str(tmp_path / "c.sqlite"),
                        "--from-maps", str(other)], capsys)  # fmt: skip
    assert code == 2 and "a causal map of world 'indoor-life-0000-seed-0', not of " \
        "'indoor-life-0001-seed-0'" in err, err
    (other / saved.name).write_bytes(saved.read_bytes()[:200])
    code, _, err = run([*base, "-o", str(tmp_path / "c.sqlite"), "--from-maps", str(other)],
                       capsys)  # fmt: skip
    assert code == 2 and "not a complete .npz archive" in err and "Traceback" not in err
    assert not (tmp_path / "c.sqlite").exists()


def test_a_world_with_no_valid_tasks_is_recorded_as_skipped(
    learnt: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    import copi.experiments.lifelong as lifelong
    from copi.errors import InvalidWorldError
    from copi.reports import write_lifelong_report

    real = lifelong.draw_life

    def draw(family: str, life: int, *args: Any, **kwargs: Any) -> Any:
        if life == 1:
            raise InvalidWorldError("no two points 10 apart")
        return real(family, life, *args, **kwargs)

    monkeypatch.setattr(lifelong, "draw_life", draw)
    cfg = LifelongConfig(learnt, worlds=2, tasks=2, methods=("compass-guard@sensor:mapping",))
    out = tmp_path / "s.sqlite"
    run_lifelong(cfg, out, workers=1)
    rows = _rows(out)
    assert [r["outcome"] for r in rows if r["life"] == 1] == ["skipped", "skipped"]
    run_lifelong(cfg, out, workers=1)  # nothing left to do
    assert _rows(out) == rows
    text = write_lifelong_report(out, tmp_path / "s.md").read_text()
    assert "1 worlds (lives)" in text  # the skipped life counts in no rate


def test_an_older_store_gains_the_lifelong_table_and_runs_are_reported_apart(
    learnt: str, tmp_path: Path
) -> None:
    from copi.reports import write_lifelong_report

    out = tmp_path / "old.sqlite"
    with ResultsStore(out):
        pass
    with sqlite3.connect(out) as db:  # as a store written before Experiment 3
        db.execute("DROP TABLE lifelong")
    for family in ("indoor", "star"):
        cfg = LifelongConfig(learnt, family=family, worlds=1, tasks=2,
                             methods=("compass-guard@sensor:mapping",))  # fmt: skip
        run_lifelong(cfg, out, workers=1)
    rows = _rows(out)
    assert len(rows) == 4 and {r["family"] for r in rows} == {"indoor", "star"}
    text = write_lifelong_report(out, tmp_path / "r.md").read_text()
    assert text.count("# Experiment 3") == 2  # two families' lives: never pooled
    assert (tmp_path / "r.png").exists() and (tmp_path / "r-2.png").exists()


def test_saved_maps_identify_a_run_whatever_its_worlds(learnt: str, tmp_path: Path) -> None:
    maps = tmp_path / "maps"
    first = LifelongConfig(learnt, worlds=2, tasks=1, methods=("copi-learnt@sensor:causal",),
                           maps=str(maps))  # fmt: skip
    run_lifelong(first, tmp_path / "a.sqlite", workers=1)
    one = LifelongConfig(learnt, worlds=1, tasks=1, methods=("copi-learnt@sensor:causal",),
                         from_maps=str(maps)).resolved()  # fmt: skip
    two = LifelongConfig(learnt, worlds=2, tasks=1, methods=("copi-learnt@sensor:causal",),
                         from_maps=str(maps)).resolved()  # fmt: skip
    assert one.run_id(one.methods[0]) == two.run_id(two.methods[0])
    with pytest.raises(ValueError, match="--maps and --from-maps are both"):
        LifelongConfig(learnt, worlds=1, tasks=1, methods=("copi-learnt@sensor:causal",),
                       from_maps=str(maps), maps=str(maps)).resolved()  # fmt: skip


def test_goals_set_rates_side_by_side_only_over_the_lives_both_ran(
    learnt: str, tmp_path: Path
) -> None:
    from copi.reports import write_lifelong_report
    from copi.reports._lifelong import CAUSAL

    out = tmp_path / "s.sqlite"
    run_lifelong(LifelongConfig(learnt, worlds=2, tasks=5, methods=(CAUSAL,)), out, workers=1)
    run_lifelong(LifelongConfig(learnt, worlds=1, tasks=5, methods=("copi-learnt@map",)), out,
                 workers=1)  # fmt: skip
    rows = _rows(out)
    on_life_0 = [r for r in rows if r["life"] == 0 and r["task"] == 4]
    assert len(on_life_0) == 2  # both ran life 0's last task
    text = write_lifelong_report(out, tmp_path / "s.md").read_text()
    (goal,) = [ln for ln in text.splitlines() if "vs the learnt preset" in ln]
    assert "(on the 1 lives both ran)" in goal, goal
    causal = next(r for r in on_life_0 if r["strategy"] == "causal")
    assert f"late success {100.0 * (causal['outcome'] == 'success'):.1f} vs" in goal, goal
