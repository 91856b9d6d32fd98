from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from copi.reports._navigation import _fig3, _fig4, _outcome_title
from tests.common import SQUARE_ROOM


def test_fig4_without_any_success_draws_no_empty_legend(tmp_path: Path) -> None:
    # a legend with no labelled artist warns, and warnings are errors here
    path = _fig4({"straight": np.array([]), "dwa": np.array([np.nan])}, tmp_path)
    assert path.exists()


def test_fig4_puts_the_tail_in_a_labelled_last_bin(tmp_path: Path) -> None:
    rng = np.random.default_rng(0)
    excess = {"a": rng.exponential(0.3, 500), "b": np.append(rng.exponential(0.2, 300), 40.0)}
    drawn = []
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr("copi.reports._figures.save_figure", lambda fig, path: drawn.append(fig))
        assert _fig4(excess, tmp_path) == tmp_path / "fig4_excess.png"
    ax = drawn[0].axes[0]
    hi = max(float(np.percentile(100 * np.concatenate(list(excess.values())), 98)), 50.0)
    assert ax.get_xticklabels()[-1].get_text() == f"> {hi:.0f}"
    # the count each method has beyond the threshold, written over the last bin
    counts = sorted(t.get_text() for t in ax.texts)
    assert counts == sorted(str(int((100 * e > hi).sum())) for e in excess.values())
    assert int((100 * excess["b"] > hi).sum()) >= 1  # the 4000 % outlier among them
    labels = ax.get_legend_handles_labels()[1]
    assert "a (500 successful episodes)" in labels and "b (301 successful episodes)" in labels
    assert f"b: median {100 * np.median(excess['b']):.1f} %" in labels


def test_fig3_titles_say_each_outcome(tmp_path: Path) -> None:
    traj = {
        "world": SQUARE_ROOM.to_dict(),
        "path": [[2.0, 2.0], [3.0, 2.0], [4.0, 2.0]],
        "traces": [[[10.0, 10.0]], [[10.5, 10.0]], [[11.0, 10.0]]],
        "radii": [0.5],
        "goal": [15.0, 15.0],
    }
    titles = [
        _outcome_title({**traj, "episode": k, "outcome": o})[0]
        for k, o in enumerate(["success", "collision", "timeout"])
    ]
    assert titles == [
        "episode 0: success in 2 steps",
        "episode 1: collision at step 2",
        "episode 2: timeout after 2 steps",
    ]
    assert _outcome_title({**traj, "episode": 3})[0] == "episode 3: 2 steps (outcome not recorded)"
    picks = [{**traj, "episode": k, "outcome": o} for k, o in enumerate(["success", "collision"])]
    assert _fig3(picks, tmp_path, "dwa") == tmp_path / "fig3_dwa.png"
