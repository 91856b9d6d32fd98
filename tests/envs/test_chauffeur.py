"""The homicidal chauffeur as a PettingZoo ParallelEnv: the API, and what it draws."""

from __future__ import annotations

import warnings

import numpy as np

from copi.envs.chauffeur import parallel_env
from copi.world._render import GOAL, PURSUER


def _rgb(color: str) -> np.ndarray:
    return np.array([int(color[i : i + 2], 16) for i in (1, 3, 5)])


def _near(img: np.ndarray, color: str, point: np.ndarray, radius: int) -> int:
    x, y = point
    patch = img[max(0, y - radius) : y + radius + 1, max(0, x - radius) : x + radius + 1]
    return int((np.abs(patch.astype(int) - _rgb(color)).sum(-1) < 30).sum())


def test_render_draws_the_pursuer_and_no_goal() -> None:
    env = parallel_env(render_mode="rgb_array")
    env.reset(seed=1)
    for _ in range(5):
        env.step({a: env.action_space(a).sample() for a in env.agents})
    img = env.render()
    assert img is not None and img.shape == (400, 400, 3)
    assert env.game is not None
    # where the car is in the image: the same fit as the rasteriser's
    xmin, ymin, xmax, ymax = env.game.world.bounds
    pad = 0.03 * max(xmax - xmin, ymax - ymin)
    scale = min(400 / (xmax - xmin + 2 * pad), 400 / (ymax - ymin + 2 * pad))
    cx = 200 + scale * (env.game.car.position[0] - 0.5 * (xmin + xmax))
    cy = 200 - scale * (env.game.car.position[1] - 0.5 * (ymin + ymax))
    assert _near(img, PURSUER, np.array([round(cx), round(cy)]), 6) > 10
    assert _near(img, GOAL, np.array([200, 200]), 200) == 0  # no goal star anywhere


def test_pettingzoo_parallel_api() -> None:
    from pettingzoo.test import parallel_api_test

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        parallel_api_test(parallel_env(), num_cycles=200)
        parallel_api_test(parallel_env(dynamic=False), num_cycles=100)
    env = parallel_env(render_mode="rgb_array")
    obs, _ = env.reset(seed=1)
    assert obs["evader"].shape == (36,) and obs["pursuer"].shape == (2,)
    img = env.render()
    assert img is not None and img.shape[2] == 3
