"""The environment a local policy learns in: its steps are refused before a reset, after
the episode's end, and for actions that are not 2 real numbers; its arguments out of range
are refused in one line when it is made, and a family whose sampler raises at a reset,
naming the family and the error."""

from __future__ import annotations

import re
from typing import Any

import gymnasium
import numpy as np
import pytest

from copi.envs.local_policy import LocalPolicyEnv
from copi.errors import InvalidArgumentError


def test_bad_steps_are_refused_in_one_line() -> None:
    with pytest.raises(InvalidArgumentError, match="max_steps must be a positive int, at most"):
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


SEEDS = "seed_of_episodes must be an int in 0 .. 9223372036854775807; got "
STEPS = "max_steps must be a positive int, at most 1,000,000 (steps of one episode); got "


@pytest.mark.parametrize(
    ("kw", "message"),
    [
        ({"levels": ()}, "levels must be a non-empty tuple of sensing level names; got ()"),
        ({"levels": "map"}, "levels must be a non-empty tuple of sensing level names; got 'map'"),
        ({"levels": ("map", None)}, "levels must be a non-empty tuple of sensing level names"),
        ({"levels": ("oracle",)}, "a local policy runs at sensor or map, not oracle"),
        ({"levels": ("sky",)}, "sensing level must be one of"),
        ({"families": ()}, "families must be a non-empty tuple of family names; got ()"),
        ({"families": "star"}, "families must be a non-empty tuple of family names; got 'star'"),
        ({"families": (["star"],)}, "families must be a non-empty tuple of family names"),
        ({"families": ("moon",)}, "family must be one of"),
        ({"seed_of_episodes": float("nan")}, SEEDS + "nan"),
        ({"seed_of_episodes": -1}, SEEDS + "-1"),
        ({"seed_of_episodes": 2**64}, SEEDS + str(2**64)),
        ({"seed_of_episodes": 2.0}, SEEDS + "2.0"),
        ({"seed_of_episodes": True}, SEEDS + "True"),
        ({"seed_of_episodes": "2"}, SEEDS + "'2'"),
        ({"max_steps": 0}, STEPS + "0"),
        ({"max_steps": float("inf")}, STEPS + "inf"),
        ({"max_steps": float("nan")}, STEPS + "nan"),
        ({"max_steps": 2.5}, STEPS + "2.5"),
        ({"max_steps": 10**7}, STEPS + "10000000"),
        ({"max_steps": True}, STEPS + "True"),
        ({"task": "fly"}, "task must be navigation or chauffeur; got 'fly'"),
        ({"reward": {"success": 1.0}}, "reward must be a copi.envs.local_policy.Reward or None"),
    ],
)
def test_bad_arguments_are_refused_when_the_env_is_made(kw: dict[str, Any], message: str) -> None:
    with pytest.raises(InvalidArgumentError, match="^" + re.escape(message)) as err:
        LocalPolicyEnv(**kw)
    assert "\n" not in str(err.value)


def test_the_arguments_it_takes_make_an_env_that_resets() -> None:
    env = LocalPolicyEnv(["star"], levels=["sensor"], max_steps=np.int64(3),
                         seed_of_episodes=np.uint32(7))  # fmt: skip
    obs, _ = env.reset(seed=0)
    assert env.levels == ("sensor",) and env.max_steps == 3 and env.seed_of_episodes == 7
    assert type(env.max_steps) is int and type(env.seed_of_episodes) is int
    assert env.observation_space.contains(obs)


def test_a_family_whose_sampler_raises_is_named_at_the_reset() -> None:
    from copi.world import register_family, unregister_family

    def sampler(rng: np.random.Generator, *, name: str | None = None) -> Any:
        raise ZeroDivisionError("no worlds today")

    register_family("fz-broken", sampler, summary="a family whose sampler raises")
    try:
        env = LocalPolicyEnv(("fz-broken",))
        with pytest.raises(InvalidArgumentError) as err:
            env.reset(seed=0)
    finally:
        unregister_family("fz-broken")
    assert str(err.value) == ("the sampler of family 'fz-broken' raised ZeroDivisionError: "
                              "no worlds today")  # fmt: skip


def test_a_family_with_no_valid_episode_says_why() -> None:
    """Worlds with no valid task are skipped (another is drawn); when 20 in a row are,
    the error says what was wrong with the last."""
    from copi.world import ObstacleSpec, World, register_family, unregister_family

    def tiny(rng: np.random.Generator, *, name: str | None = None) -> World:
        return World(np.array([[0, 0], [2, 0], [2, 2], [0, 2]]), name=name or "tiny",
                     obstacles=ObstacleSpec(count=(0, 0)))  # fmt: skip

    register_family("fz-tiny", tiny, summary="a world too small for a task")
    try:
        env = LocalPolicyEnv(("fz-tiny",))
        with pytest.raises(InvalidArgumentError, match=r"^no valid episode of fz-tiny near "
                           r"episode \d+ in 20 draws \(the last: world 'fz-tiny-\d+': found "
                           r"no free start and goal 10 apart"):  # fmt: skip
            env.reset(seed=0)
    finally:
        unregister_family("fz-tiny")
