from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from copi.reports import save_episode_gif, save_episode_png
from copi.world import Simulator, random_walk_episodes
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


def test_the_capability_figures_show_what_they_say(faithful_caps, tmp_path: Path) -> None:
    """The context map draws a spanning tree of the map (one edge fewer than nodes per
    piece, not the hairball of every edge), and the H(k) plot's legend names its curve,
    the rule's criterion and the refinement kept."""
    from matplotlib.collections import LineCollection
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    from copi.learning import Capabilities
    from copi.reports import _capabilities as cf
    from copi.reports import _figures

    caps = Capabilities.load(faithful_caps)
    drawn = []
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(_figures, "save_figure", lambda fig, path: drawn.append(fig) or path)
        cf.save_context_map(caps, tmp_path)
        cf.save_skeleton_curve(caps, tmp_path)
    (lines,) = [c for c in drawn[0].axes[0].collections if isinstance(c, LineCollection)]
    n = len(caps.nodes)
    e = np.asarray(caps.edges).reshape(-1, 2)
    pieces = connected_components(coo_matrix((np.ones(len(e)), (e[:, 0], e[:, 1])),
                                             shape=(n, n)), directed=False)[0]  # fmt: skip
    assert len(lines.get_segments()) == n - pieces < len(e)
    labels = [t.get_text() for t in drawn[1].axes[0].get_legend().get_texts()]
    assert labels == ["H(k), Hausdorff distance to the map",
                      "the rule's criterion (right axis)", "the refinement kept"]  # fmt: skip
