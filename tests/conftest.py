"""Fixtures shared across the test packages: small capabilities files, learnt once per
test process."""

from __future__ import annotations

from pathlib import Path

import pytest

from copi.learning import LearnParams, learn

# tests/plugin holds a package standing for a user's (loaded through its entry points by
# the tests that put it on the path): never collected, never imported on its own
collect_ignore = ["plugin"]


@pytest.fixture(scope="session")
def learnt_caps(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A small capabilities file of the learnt preset (16 directions, safety priors)."""
    path = tmp_path_factory.mktemp("caps") / "capabilities-learnt.npz"
    learn(LearnParams(worlds=6, steps=150, directions=16, safety=True, probe_worlds=6,
                      probe_steps=60, seed=1)).save(path)  # fmt: skip
    return path


@pytest.fixture(scope="session")
def faithful_caps(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A small capabilities file of the faithful preset (4 directions)."""
    path = tmp_path_factory.mktemp("caps") / "capabilities-faithful.npz"
    learn(LearnParams(worlds=6, steps=150, directions=4, seed=1)).save(path)
    return path


@pytest.fixture(scope="session")
def predictive_caps(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A small capabilities file of the predictive preset (a model of what moves, safety
    networks that see the static reading)."""
    path = tmp_path_factory.mktemp("caps") / "capabilities-predictive.npz"
    learn(LearnParams(worlds=6, steps=150, directions=16, safety=True, safety_static=True,
                      predict=True, probe_worlds=4, probe_steps=40, predict_worlds=12,
                      predict_steps=120, seed=1)).save(path)  # fmt: skip
    return path
