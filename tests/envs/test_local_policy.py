"""The environment a local policy learns in: its steps are refused before a reset, after
the episode's end, and for actions that are not 2 real numbers."""

from __future__ import annotations

import gymnasium
import numpy as np
import pytest

from copi.envs.local_policy import LocalPolicyEnv
from copi.errors import InvalidArgumentError


def test_bad_steps_are_refused_in_one_line() -> None:
    with pytest.raises(InvalidArgumentError, match="max_steps must be a positive int; got 0"):
        LocalPolicyEnv(max_steps=0)
    env = LocalPolicyEnv(("star",), max_steps=2)
    with pytest.raises(gymnasium.error.ResetNeeded, match="call reset"):
        env.step(np.zeros(2, dtype=np.float32))
    env.reset(seed=0)
    with pytest.raises(InvalidArgumentError, match=r"shape \(2,\); got float64 values of shape"):
        env.step(np.zeros((2, 1)))
    with pytest.raises(InvalidArgumentError, match="got complex128"):
        env.step(np.array([1j, 0]))
    ended = False
    for _ in range(2):
        *_, terminated, truncated, _ = env.step(np.zeros(2, dtype=np.float32))
        ended = terminated or truncated
    assert ended
    with pytest.raises(gymnasium.error.ResetNeeded, match="the episode has ended"):
        env.step(np.zeros(2, dtype=np.float32))
