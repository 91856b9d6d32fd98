"""The one episode API (copi.runs.Episode) is the sequence the benchmark stores, and the
one input resolver checks what a run reads before anything is written."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from copi.core import Agent
from copi.errors import InvalidArgumentError, MethodError
from copi.experiments import BenchmarkConfig, NavigationConfig, evaluate, run_benchmark
from copi.methods import make_agent
from copi.results import EpisodeRow, ResultsStore
from copi.runs import Episode, resolve_inputs, step_limit

TIMINGS = {"decision_us", "strategy_us", "run_id", "experiment", "method"}


def _same(a: EpisodeRow, b: EpisodeRow) -> bool:
    def clean(v: object) -> object:
        return None if isinstance(v, float) and math.isnan(v) else v

    return all(clean(a[k]) == clean(b[k]) for k in a.keys() if k not in TIMINGS)


def test_an_episode_s_rows_are_the_benchmark_s(tmp_path: Path) -> None:
    out = tmp_path / "b.sqlite"
    run_benchmark(BenchmarkConfig(methods=("dwa@map", "straight@sensor"), families=("crowd",),
                                  episodes=3), out)  # fmt: skip
    with ResultsStore(out, readonly=True) as store:
        stored = {(r.method, r.sensing, r.episode): r for r in store.episodes()}
    for k in range(3):
        episode = Episode.draw("crowd", k, seed=0)
        assert episode.max_steps == step_limit(episode.optimal)
        for method, level in (("dwa", "map"), ("straight", "sensor")):
            row = episode.row(make_agent(method), sensing=level)  # type: ignore[arg-type]
            assert _same(row, stored[method, level, k]), (method, level, k)


def test_running_an_episode_leaves_it_as_drawn() -> None:
    episode = Episode.draw("star", 2, seed=5)
    before = (episode.sim.position.copy(), episode.sim.centers.copy(), episode.sim.t)
    first = episode.run(make_agent("dwa"), sensing="map")
    again = episode.run(make_agent("dwa"), sensing="map")
    assert first.steps > 0 and (first.outcome, first.steps, first.path_length) == (
        again.outcome, again.steps, again.path_length)  # fmt: skip
    assert np.array_equal(episode.sim.position, before[0]) and episode.sim.t == before[2]
    assert np.array_equal(episode.sim.centers, before[1])


def test_resolving_inputs_refuses_a_method_without_its_capabilities() -> None:
    with pytest.raises(InvalidArgumentError, match="copi-learnt needs the 'learnt'"):
        resolve_inputs(methods=["copi-learnt"])
    found = resolve_inputs(methods=["dwa", "ppo-star"], families=["star", "maps"])
    assert set(found.families) == {"star", "maps"} and "maps_sha" in found.families["maps"]
    assert found.methods["dwa"] == {} and set(found.methods["ppo-star"]) == {"weights_sha"}


def test_a_method_s_weights_are_not_taken_for_its_family_s_data(tmp_path: Path) -> None:
    """Experiment 1 of a method that reads weights runs (its weights' hash is part of
    the run's identity, apart from the family's data it checks on every episode)."""
    config = NavigationConfig(None, method="ppo-star", worlds=2, max_steps=50)
    run = evaluate(config, tmp_path / "r.sqlite")
    with ResultsStore(tmp_path / "r.sqlite", readonly=True) as store:
        (stored,) = store.runs()
        assert len(store.episodes(run)) == 2
    resolved = config.resolved()
    assert resolved.inputs == {} and set(resolved.method_inputs) == {"weights_sha"}
    assert stored.config["weights_sha"] == resolved.method_inputs["weights_sha"]


class _CtrlCInCompiledCall(Agent):
    """As numba reports a Ctrl-C that lands inside a compiled call: a SystemError raised
    while the KeyboardInterrupt was being handled."""

    name = "ctrl-c-in-numba"

    def __init__(self, where: str) -> None:
        self.where = where

    def _pressed(self) -> None:
        try:
            raise KeyboardInterrupt
        except KeyboardInterrupt:
            raise SystemError("returned a result with an exception set") from None

    def reset(self, task: object) -> None:
        if self.where == "reset":
            self._pressed()

    def act(self, obs: object) -> np.ndarray:
        if self.where == "act":
            self._pressed()
        return np.zeros(2)


@pytest.mark.parametrize("where", ["reset", "act"])
def test_a_ctrl_c_inside_a_method_s_compiled_call_is_the_user_s_not_the_method_s(
    where: str,
) -> None:
    ep = Episode.draw("star", 0, seed=0)
    with pytest.raises(KeyboardInterrupt):
        ep.run(_CtrlCInCompiledCall(where), sensing="map")
    with pytest.raises(MethodError, match="act at step 1"):  # a SystemError of its own
        ep.run(_Raising(SystemError("its own")), sensing="map")


class _Raising(Agent):
    name = "raising"

    def __init__(self, exc: BaseException) -> None:
        self.exc = exc

    def reset(self, task: object) -> None:
        pass

    def act(self, obs: object) -> np.ndarray:
        raise self.exc
