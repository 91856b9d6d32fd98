"""Experiment 1 runs every registered method the benchmark runs (copi evaluate once
refused the PPO peers, taking their weights for a change of the family's data)."""

from __future__ import annotations

from pathlib import Path

import pytest

from copi.experiments import NavigationConfig, evaluate
from copi.learning import LearnParams, learn
from copi.methods import method_names, method_spec
from copi.results import ResultsStore

SLOW = {"model-oracle"}  # seconds an episode: run by the benchmark's own tests


@pytest.fixture(scope="module")
def presets(tmp_path_factory: pytest.TempPathFactory, learnt_caps: Path,
            faithful_caps: Path) -> dict[str, str]:  # fmt: skip
    d = tmp_path_factory.mktemp("presets")
    out = {"learnt": str(learnt_caps), "faithful": str(faithful_caps)}
    for name, params in (("extended", LearnParams(worlds=6, steps=150, directions=16, seed=1)),
                         ("learnt-motion", LearnParams(worlds=4, steps=100, directions=16,
                                                       safety=True, motion=True, probe_worlds=4,
                                                       probe_steps=40, seed=1)),
                         ("predictive", LearnParams(worlds=4, steps=100, directions=16,
                                                    safety=True, safety_static=True,
                                                    predict=True, probe_worlds=4, probe_steps=40,
                                                    predict_worlds=4, predict_steps=60, seed=1))):  # fmt: skip
        learn(params).save(d / f"{name}.npz")
        out[name] = str(d / f"{name}.npz")
    return out


@pytest.mark.parametrize("name", [n for n in method_names() if n not in SLOW])
def test_evaluate_runs_the_method(name: str, presets: dict[str, str], tmp_path: Path) -> None:
    spec = method_spec(name)
    if not spec.available():
        pytest.skip(f"{name} needs {spec.missing}")
    config = NavigationConfig(presets.get(spec.capabilities or "", None)
                              if spec.capabilities else None, method=name, worlds=1,
                              max_steps=60, sensing=spec.levels[-1], family="polygon")  # fmt: skip
    run = evaluate(config, tmp_path / "r.sqlite")
    with ResultsStore(tmp_path / "r.sqlite", readonly=True) as store:
        (row,) = store.episodes(run)
    assert row.method == name and row.outcome in ("success", "collision", "timeout")
