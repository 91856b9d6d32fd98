from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from copi.errors import InvalidArgumentError
from copi.learning import LearnParams, explore, learn


def test_exploration_is_the_same_whatever_the_workers() -> None:
    a = explore(3, 40, seed=7, workers=1)
    b = explore(3, 40, seed=7, workers=2)
    np.testing.assert_array_equal(a.readings, b.readings)
    np.testing.assert_array_equal(a.moves, b.moves)
    assert a.readings.shape == (120, 32)
    assert (a.readings >= 0).all() and (a.readings <= 10).all()
    assert (np.hypot(*a.moves.T) <= 1 + 1e-12).all()


def test_learn_is_deterministic_and_reports_every_stage() -> None:
    p = LearnParams(worlds=5, steps=120, seed=3)
    a, b = learn(p), learn(p)
    assert a.equals(dataclasses.replace(b, stats=a.stats))  # all but the timings
    stages = [s["stage"] for s in a.stats["stages"]]
    assert stages == ["explore", "context map (GNG)", "skeleton", "symmetry", "policies"]
    assert a.stats["stages"][0]["samples"] == 600
    c = learn(LearnParams(worlds=5, steps=120, seed=4))
    assert a.nodes.shape != c.nodes.shape or not np.array_equal(a.nodes, c.nodes)


def test_forced_landmarks_and_progress_calls() -> None:
    calls = []
    caps = learn(LearnParams(worlds=4, steps=120, landmarks=9), progress=lambda *x: calls.append(x))
    assert caps.landmarks.n_landmarks == 9
    assert {c[0] for c in calls} == {"explore", "context map", "skeleton", "policies"}
    assert ("explore", 4, 4) in calls


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"worlds": 0}, "worlds must be a positive int"),
        ({"directions": 6}, "directions must be 4, 8 or 16"),
        ({"learner": "ppo"}, "learner must be 'astar' or 'value-iteration'"),
        ({"symmetry_tol": -1.0}, "symmetry_tol must be >= 0"),
        ({"symmetry_quantile": 101.0}, "symmetry_quantile must be in"),
    ],
)
def test_bad_params(kwargs, message) -> None:
    with pytest.raises(InvalidArgumentError, match=message):
        LearnParams(**kwargs)
