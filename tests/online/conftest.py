from __future__ import annotations

import pytest

from copi.learning import Capabilities, LearnParams, learn


@pytest.fixture(scope="session")
def small_caps(tmp_path_factory: pytest.TempPathFactory) -> tuple[Capabilities, str]:
    caps = learn(LearnParams(worlds=12, steps=200, seed=2, directions=8))
    path = tmp_path_factory.mktemp("caps") / "caps.npz"
    caps.save(path)
    return caps, str(path)
