"""Crowds of registered methods (copi.experiments.crowd): the batched decisions are the
per-agent ones, the trajectories do not depend on the processes or the executor (1 or 2
local processes, Dask), a sweep resumes, and bad configurations are refused."""

from __future__ import annotations

import os
import sqlite3
from pathlib import Path

import numpy as np
import pytest

from copi.errors import InvalidArgumentError
from copi.experiments._crowd_drive import AgentsDriver, BatchDriver, Team, slices
from copi.experiments.crowd import CrowdConfig, draw_crowd, run_crowd, run_crowds
from copi.learning import Capabilities
from copi.methods import make_agent, method_spec
from copi.online import LearntAgent
from copi.results import ResultsStore


def _config(caps: Path, **kw: object) -> CrowdConfig:
    base: dict[str, object] = {"agents": 60, "methods": ("copi-learnt", "compass-guard"),
                               "densities": (0.05, 0.3), "runs": 2, "steps": 15,
                               "capabilities": {"learnt": str(caps)}}  # fmt: skip
    base.update(kw)
    return CrowdConfig(**base)  # type: ignore[arg-type]


def _rows(path: Path) -> list[tuple[object, ...]]:
    with ResultsStore(path, readonly=True) as store:
        return sorted(
            (r.method, r.world, r.life, r.task, r.outcome, r.steps, r.path_length)
            for r in store.lifelong()
        )


@pytest.mark.parametrize(("steady", "beta"), [(False, 0.0), (True, 0.0), (True, 0.5)])
def test_batched_decisions_are_each_agent_s_own(learnt_caps: Path, steady: bool,
                                                beta: float) -> None:  # fmt: skip
    # beta 0: decide_rows on the crowd's arrays; beta > 0: decide_batch, the context recognised
    caps = Capabilities.load(learnt_caps)
    cfg = _config(learnt_caps, agents=80, densities=(0.2,), steady=steady)
    paths = []
    for kind in ("batch", "each"):
        crowd = draw_crowd(cfg, 0.2, 0)

        def make(lo: int, hi: int, kind: str = kind, crowd: object = crowd) -> object:
            if kind == "batch":
                agent = make_agent("copi-learnt", caps, beta=beta)
                assert isinstance(agent, LearntAgent)
                return BatchDriver(agent, crowd, lo, hi)  # type: ignore[arg-type]
            spec = method_spec("copi-learnt")
            return AgentsDriver(lambda: spec.make(caps, beta=beta), crowd, "sensor", lo, hi)  # type: ignore[arg-type]

        with Team(crowd, make) as team:  # type: ignore[arg-type]
            for _ in range(25):
                crowd.step(team.decide(), leave=not steady, sense=False)
        paths.append((crowd.positions.copy(), crowd.outcome.copy(), crowd.goals.copy()))
    for a, b in zip(*paths, strict=True):
        assert np.array_equal(a, b)


def test_one_run_is_the_same_on_one_or_two_processes(learnt_caps: Path) -> None:
    assert slices(600, 2) == [(0, 300), (300, 600)]
    assert slices(300, 2) == [(0, 300)]  # too few agents for a second process
    # a steady crowd's next step is sensed in the other process while this one keeps
    # the books (the batched driver); trips that end leave the world first
    for method, steady in (("copi-learnt", True), ("copi-learnt", False),
                           ("compass-guard", False)):  # fmt: skip
        cfg = _config(learnt_caps, agents=600, densities=(0.2,), steps=12,
                      methods=(method,), steady=steady).resolved()  # fmt: skip
        one = run_crowd(cfg, method, 0.2, 0, processes=1)
        two = run_crowd(cfg, method, 0.2, 0, processes=2)
        assert (one.processes, two.processes) == (1, 2)
        assert np.array_equal(one.crowd.positions, two.crowd.positions)
        assert [r.as_dict() | {"decision_us": 0} for r in one.rows] == [
            r.as_dict() | {"decision_us": 0} for r in two.rows
        ]


def test_a_sweep_is_the_same_inline_on_a_pool_and_on_dask(learnt_caps: Path, tmp_path: Path) -> None:
    from distributed import LocalCluster

    cfg = _config(learnt_caps)
    run_crowds(cfg, tmp_path / "inline.sqlite", workers=1)
    run_crowds(cfg, tmp_path / "pool.sqlite", workers=2)
    # a free port for the scheduler's HTTP server (None means 8787, which a test running
    # beside this one may hold)
    with LocalCluster(n_workers=1, threads_per_worker=2, processes=False,
                      dashboard_address=":0", silence_logs=50) as cluster:  # fmt: skip
        run_crowds(cfg, tmp_path / "dask.sqlite", scheduler=cluster.scheduler_address)
    rows = _rows(tmp_path / "inline.sqlite")
    assert len(rows) == 2 * 2 * 2 * 60
    assert rows == _rows(tmp_path / "pool.sqlite") == _rows(tmp_path / "dask.sqlite")
    assert {r[4] for r in rows} <= {"success", "collision", "timeout"}


def test_a_sweep_resumes_a_lost_run_whole(learnt_caps: Path, tmp_path: Path) -> None:
    cfg = _config(learnt_caps, methods=("compass-guard",), densities=(0.1,), runs=3)
    out = tmp_path / "r.sqlite"
    ids, kept = run_crowds(cfg, out, record_every=2)
    assert kept is not None and len(kept.crowd.frames) == 15 // 2 + 1
    full = _rows(out)
    with sqlite3.connect(out) as db:
        db.execute("DELETE FROM lifelong WHERE life = 1")
    seen: list[int] = []
    run_crowds(cfg, out, progress=lambda done, total: seen.append(done))
    assert _rows(out) == full
    assert seen[0] == 2 * 15 and seen[-1] == 3 * 15  # two runs stored, one run again
    assert list(ids) == [("compass-guard", 0.1)]


def test_an_oracle_method_sees_its_neighbours(tmp_path: Path) -> None:
    pytest.importorskip("navground.core")
    cfg = CrowdConfig(agents=30, methods=("navground-orca",), densities=(0.1,), steps=8)
    run = run_crowd(cfg.resolved(), "navground-orca", 0.1, 0)
    assert run.rows[0].sensing == "oracle" and len(run.rows) == 30
    assert run.steps == 8 or not run.crowd.active.any()


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"methods": ("nosuch",)}, "method must be one of"),
        ({"methods": ("clairvoyant",)}, "the future of every moving body"),
        ({"methods": ("replan",), "sensing": "map"}, "needs sensing level 'oracle'"),
        ({"methods": ("copi-learnt",), "capabilities": {}}, "needs the 'learnt' capabilities"),
        ({"agents": 0}, "agents must be a positive int"),
        ({"agents": 200_000}, "agents must be at most 100,000"),
        ({"steps": 100_001}, "steps must be at most 100,000"),
        ({"densities": (0.1, 9.0)}, "density must be at most 2.7"),
        ({"densities": ()}, "at least one density"),
        ({"agents": 100_000, "runs": 200}, "agents x runs x densities must be at most"),
        ({"sensing": "future"}, "sensing must be sensor, map or oracle"),
    ],
)
def test_bad_configurations_are_refused(kwargs: dict[str, object], message: str) -> None:
    base: dict[str, object] = {"methods": ("compass-guard",)}
    base.update(kwargs)
    with pytest.raises(InvalidArgumentError, match=message):
        CrowdConfig(**base)  # type: ignore[arg-type]


def test_a_crowd_that_cannot_be_placed_is_refused_before_the_store(tmp_path: Path) -> None:
    cfg = CrowdConfig(agents=400, methods=("compass-guard",), densities=(0.1, 2.2))
    with pytest.raises(InvalidArgumentError, match="cannot place 400 agents"):
        run_crowds(cfg, tmp_path / "x.sqlite")
    assert not (tmp_path / "x.sqlite").exists()


_PARENT = os.getpid()


class _Breaks:
    """A method whose act raises in any process but the test's (a crowd's worker)."""

    def __new__(cls) -> object:
        from copi.core import Agent

        class Breaks(Agent):
            name = "crowd-breaks"

            def reset(self, task: object) -> None:
                pass

            def act(self, obs: object) -> np.ndarray:
                if os.getpid() != _PARENT:
                    raise RuntimeError("broken on purpose")
                return np.zeros(2)

        return Breaks()


def test_a_method_that_breaks_in_a_worker_is_one_error_naming_it() -> None:
    from copi.errors import MethodError
    from copi.methods import register_method, unregister_method

    register_method("crowd-breaks", _Breaks, summary="raises", replace=True)
    try:
        cfg = CrowdConfig(agents=600, methods=("crowd-breaks",), densities=(0.2,), steps=3)
        run = run_crowd(cfg.resolved(), "crowd-breaks", 0.2, 0, processes=1)
        assert run.steps == 3
        with pytest.raises(MethodError, match="method 'crowd-breaks': act at step 1 raised "
                                              "RuntimeError: broken on purpose"):
            run_crowd(cfg.resolved(), "crowd-breaks", 0.2, 0, processes=2)
    finally:
        unregister_method("crowd-breaks")
