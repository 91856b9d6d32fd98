from __future__ import annotations

from pathlib import Path

import pytest

from copi.experiments import random_walk_episodes, save_episode_gif, save_episode_png
from copi.world import Simulator
from tests.common import PILLARS, U_TRAP


def test_episodes_are_reproducible_per_index() -> None:
    a = random_walk_episodes([PILLARS, U_TRAP], seed=4, steps=30)
    b = random_walk_episodes([U_TRAP], seed=4, steps=30)
    assert len(a[0].path) == 31
    # episode k depends on (seed, k) only: U_TRAP at index 1 differs from index 0
    assert (a[1].position != b[0].position).any()
    c = random_walk_episodes([PILLARS, U_TRAP], seed=4, steps=30)
    assert all((x.position == y.position).all() for x, y in zip(a, c, strict=True))


def test_pictures_are_written(tmp_path: Path) -> None:
    (sim,) = random_walk_episodes([PILLARS], seed=0, steps=12)
    png = save_episode_png(sim, tmp_path / "p.png")
    gif = save_episode_gif(sim, tmp_path / "p.gif", max_frames=5)
    assert png.stat().st_size > 1000 and gif.read_bytes()[:6] == b"GIF89a"
    from PIL import Image

    with Image.open(gif) as im:
        assert im.n_frames == 5


def test_gif_needs_a_recorded_episode(tmp_path: Path) -> None:
    sim = Simulator.from_world(PILLARS, 0)
    with pytest.raises(ValueError, match="record=True"):
        save_episode_gif(sim, tmp_path / "x.gif")
