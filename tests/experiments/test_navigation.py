from __future__ import annotations

import os
import signal
import sqlite3
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from copi.experiments import NavigationConfig, evaluate, evaluate_episode
from copi.learning import LearnParams, learn
from copi.reports import write_report
from copi.results import ResultsError, ResultsStore

TIMINGS = {"decision_us", "strategy_us"}


@pytest.fixture(scope="module")
def caps_path(tmp_path_factory: pytest.TempPathFactory) -> str:
    path = tmp_path_factory.mktemp("caps") / "caps.npz"
    learn(LearnParams(worlds=12, steps=200, seed=1)).save(path)
    return str(path)


def _rows(path: Path) -> list[dict]:
    with ResultsStore(path) as store:
        return [{k: v for k, v in r.items() if k not in TIMINGS} for r in store.episodes()]


def test_an_episode_depends_on_its_index_only(caps_path: str) -> None:
    cfg = NavigationConfig(caps_path, worlds=5, max_steps=300).resolved()
    a = evaluate_episode(cfg, 3)
    b = evaluate_episode(cfg, 3)
    assert {k: v for k, v in a.__dict__.items() if k not in TIMINGS} == {
        k: v for k, v in b.__dict__.items() if k not in TIMINGS
    }
    assert a.path_length <= a.steps + 1e-9  # at most one agent step per time step
    assert np.isfinite(a.optimal_length)
    if a.reached:
        assert a.excess == pytest.approx(a.path_length / a.optimal_length - 1)


@pytest.mark.parametrize("end_on_contact", [True, False])
def test_outcomes_are_exclusive_and_excess_is_never_negative(
    caps_path: str, end_on_contact: bool
) -> None:
    cfg = NavigationConfig(
        caps_path, worlds=40, max_steps=150, end_on_contact=end_on_contact
    ).resolved()
    rows = [evaluate_episode(cfg, k) for k in range(40)]
    seen = set()
    for r in rows:
        flags = (r.success, r.collided, r.timed_out)
        assert sum(flags) == 1, r
        assert r.outcome == ("success", "collision", "timeout")[flags.index(True)]
        seen.add(r.outcome)
        assert r.collided == (r.contacts > 0)
        if end_on_contact:
            assert r.contacts <= 1
            assert not (r.reached and r.collided)  # a contact ends the episode first
        if r.success:
            assert r.excess >= 0.0
            assert r.time_to_goal == r.steps
        assert r.smoothness >= 0.0
        if r.collided:
            assert r.min_clearance <= 1e-9
    assert {"success", "collision"} <= seen  # the faithful chain both succeeds and touches
    if not end_on_contact:  # today's older behaviour: episodes go on after a contact
        assert any(r.contacts > 1 or (r.reached and r.collided) for r in rows)


def test_results_do_not_depend_on_the_workers(caps_path: str, tmp_path: Path) -> None:
    cfg = NavigationConfig(caps_path, worlds=12, max_steps=300)
    evaluate(cfg, tmp_path / "one.sqlite", workers=1)
    evaluate(cfg, tmp_path / "two.sqlite", workers=2)
    assert _rows(tmp_path / "one.sqlite") == _rows(tmp_path / "two.sqlite")
    assert len(_rows(tmp_path / "one.sqlite")) == 12


def test_dask_local_cluster_gives_the_same_results(caps_path: str, tmp_path: Path) -> None:
    from distributed import LocalCluster

    cfg = NavigationConfig(caps_path, worlds=6, max_steps=300)
    evaluate(cfg, tmp_path / "local.sqlite", workers=1)
    with LocalCluster(
        n_workers=1, threads_per_worker=1, processes=True, host="127.0.0.1",
        dashboard_address=":0", silence_logs=50,  # a free port: tests run side by side
    ) as cluster:  # fmt: skip
        evaluate(cfg, tmp_path / "dask.sqlite", scheduler=cluster.scheduler_address)
    assert _rows(tmp_path / "local.sqlite") == _rows(tmp_path / "dask.sqlite")


def test_rerunning_resumes_and_never_duplicates(caps_path: str, tmp_path: Path) -> None:
    cfg = NavigationConfig(caps_path, worlds=8, max_steps=300)
    out = tmp_path / "r.sqlite"
    evaluate(cfg, out)
    with sqlite3.connect(out) as db:  # lose the last three, as an interruption would
        db.execute("DELETE FROM episodes WHERE episode >= 5")
    evaluate(cfg, out)
    rows = _rows(out)
    assert [r["episode"] for r in rows] == list(range(8))
    clean = tmp_path / "clean.sqlite"
    evaluate(cfg, clean)
    assert rows == _rows(clean)


def test_a_killed_run_resumes_where_it_stopped(caps_path: str, tmp_path: Path) -> None:
    out = tmp_path / "killed.sqlite"
    args = [
        sys.executable, "-m", "copi.cli.main", "evaluate", caps_path, "-o", str(out),
        "--worlds", "150", "--max-steps", "300",
    ]  # fmt: skip
    proc = subprocess.Popen(args, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    deadline = time.time() + 120
    n = 0
    while time.time() < deadline:
        time.sleep(0.02)
        if out.exists():
            try:
                with sqlite3.connect(out, timeout=1) as db:
                    n = db.execute("SELECT COUNT(*) FROM episodes").fetchone()[0]
            except sqlite3.OperationalError:
                continue
            if n >= 5:
                break
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait()
    assert 5 <= n < 150, "the run should have been killed part-way"
    done = subprocess.run(args, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    rows = _rows(out)
    assert [r["episode"] for r in rows] == list(range(150))
    clean = tmp_path / "clean.sqlite"
    evaluate(NavigationConfig(caps_path, worlds=150, max_steps=300), clean, workers=2)
    assert rows == _rows(clean)


def test_a_different_configuration_is_refused_and_the_file_kept(
    caps_path: str, tmp_path: Path
) -> None:
    out = tmp_path / "r.sqlite"
    evaluate(NavigationConfig(caps_path, worlds=3, max_steps=300), out)
    before = out.read_bytes()
    with pytest.raises(
        ResultsError, match="different configuration .*max_steps: 300 there, 200 now"
    ):
        evaluate(NavigationConfig(caps_path, worlds=3, max_steps=200), out)
    assert out.read_bytes() == before
    foreign = tmp_path / "foreign.sqlite"
    with sqlite3.connect(foreign) as db:
        db.execute("CREATE TABLE t (x)")
    with pytest.raises(ResultsError, match="not a copi results store"):
        ResultsStore(foreign)
    (tmp_path / "text.sqlite").write_text("hello")
    with pytest.raises(ResultsError, match="not a copi results file"):
        ResultsStore(tmp_path / "text.sqlite")


def test_report_reads_everything_from_the_store(caps_path: str, tmp_path: Path) -> None:
    out = tmp_path / "r.sqlite"
    evaluate(NavigationConfig(caps_path, worlds=6, max_steps=300, record=4), out)
    evaluate(NavigationConfig(caps_path, worlds=6, max_steps=300, record=4, sensing="sensor"),
             out)  # fmt: skip
    evaluate(NavigationConfig(None, method="compass-guard", worlds=6, max_steps=300), out)
    report = write_report([out], tmp_path / "report")
    text = report.path.read_text()
    # one method at two levels: two rows that say their level, two Fig. 3 files
    assert "| copi-faithful | map | star | 6 |" in text
    assert "| copi-faithful | sensor | star | 6 |" in text
    assert "| compass-guard | map | star | 6 |" in text
    names = sorted(p.name for p in (tmp_path / "report").iterdir())
    assert "fig4_excess.png" in names
    assert {"fig3_copi_faithful__map__star.png", "fig3_copi_faithful__sensor__star.png"} <= set(
        names)


def test_a_world_file_is_run_episode_by_episode(caps_path: str, tmp_path: Path) -> None:
    from copi.world import save_worlds
    from tests.common import PILLARS, U_TRAP

    worlds = tmp_path / "w.json"
    save_worlds([U_TRAP, PILLARS], worlds)
    out = tmp_path / "r.sqlite"
    evaluate(NavigationConfig(caps_path, worlds=4, world_file=str(worlds), max_steps=300), out)
    rows = _rows(out)
    assert [r["world"] for r in rows] == ["u-trap", "pillars", "u-trap", "pillars"]
    # U_TRAP fixes start and goal, 13 apart: the frozen obstacles can only lengthen it;
    # the optimum runs to the goal's tolerance disc (0.5), as a lower bound within 0.12 %
    from copi.planning import length_error_bound

    assert rows[0]["optimal_length"] >= 13.0 / (1 + length_error_bound()) - 0.5 - 1e-9


def test_a_changed_world_file_is_refused_under_resume(tmp_path: Path) -> None:
    from copi.world import save_worlds
    from tests.common import PILLARS, U_TRAP

    worlds = tmp_path / "w.json"
    save_worlds([U_TRAP], worlds)
    out = tmp_path / "r.sqlite"
    cfg = NavigationConfig(None, method="straight", worlds=3, world_file=str(worlds), max_steps=50)
    evaluate(cfg, out)
    with sqlite3.connect(out) as db:  # an interruption after the first episode
        db.execute("DELETE FROM episodes WHERE episode >= 1")
    before = out.read_bytes()
    save_worlds([PILLARS], worlds)  # the file's content changes, its path does not
    with pytest.raises(ResultsError, match="the world file's content changed"):
        evaluate(cfg, out)
    assert out.read_bytes() == before
    # The same content at another path is the same run: it resumes.
    save_worlds([U_TRAP], worlds)
    moved = tmp_path / "moved.json"
    moved.write_bytes(worlds.read_bytes())
    evaluate(NavigationConfig(None, method="straight", worlds=3, world_file=str(moved),
                              max_steps=50), out)  # fmt: skip
    assert [r["world"] for r in _rows(out)] == ["u-trap"] * 3


def test_a_world_file_without_a_valid_task_is_refused_before_any_run(tmp_path: Path) -> None:
    from copi.errors import WorldFileError
    from copi.world import World, save_worlds
    from tests.common import U_TRAP

    worlds = tmp_path / "w.json"
    box = World([[0, 0], [4, 0], [4, 4], [0, 4]], name="box")
    save_worlds([U_TRAP, box], worlds)
    out = tmp_path / "r.sqlite"
    cfg = NavigationConfig(None, method="straight", worlds=2, world_file=str(worlds))
    with pytest.raises(WorldFileError, match=r"w\.json: world 1: world 'box': no free start"):
        evaluate(cfg, out)
    assert not out.exists()


def test_an_episode_without_a_valid_task_is_recorded_as_skipped(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    import copi.runs._draw as nav
    from copi.errors import InvalidWorldError
    from copi.reports import summarize

    real = nav.draw_episode

    def draw(family: str, k: int, *args, **kwargs):
        if k == 1:
            raise InvalidWorldError(f"world '{family}-{k:05d}': found no free start and goal")
        return real(family, k, *args, **kwargs)

    monkeypatch.setattr(nav, "draw_episode", draw)
    out = tmp_path / "r.sqlite"
    evaluate(NavigationConfig(None, method="straight", worlds=3, max_steps=30), out)
    rows = _rows(out)
    assert [r["outcome"] == "skipped" for r in rows] == [False, True, False]
    assert rows[1]["world"] == "star-00001" and "no free start" in rows[1]["reason"]
    with ResultsStore(out, readonly=True) as store:
        s = summarize(store.episodes())
    assert s["episodes"] == 2 and s["skipped"] == 1
    evaluate(NavigationConfig(None, method="straight", worlds=3, max_steps=30), out)  # done
    assert len(_rows(out)) == 3
