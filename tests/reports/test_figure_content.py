"""The report figures hold the data of their tables (not only a file on disk): each
figure is caught before it is saved and its artists are read back."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from copi.methods import MethodRun


def _caught(monkeypatch: pytest.MonkeyPatch, module: str) -> list[Any]:
    drawn: list[Any] = []
    monkeypatch.setattr(f"{module}.save_figure", lambda fig, path, **kw: drawn.append(fig))
    return drawn


def test_the_benchmark_figure_plots_each_rows_success_against_its_excess(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    from copi.reports import _benchmark as br

    def stats(success: float, excess: float) -> dict[str, float]:
        return {"success": success, "excess_median": excess}

    table = {
        "star": {MethodRun("dwa", "map", "route"): stats(0.9, 0.05),
                 MethodRun("copi-learnt", "sensor", "greedy"): stats(0.6, 0.30),
                 MethodRun("clairvoyant", "future", "route"): stats(1.0, 0.10)},
        "crowd": {MethodRun("dwa", "map", "route"): stats(0.4, 0.33),
                  MethodRun("straight", "map", "route"): stats(0.0, math.nan)},
    }  # fmt: skip
    drawn = _caught(monkeypatch, "copi.reports._figures")
    br._figure_success_excess(table, tmp_path)
    (fig,) = drawn
    for ax, family in zip(fig.axes, table, strict=False):
        assert ax.get_title() == family
        points = {}
        for coll in ax.collections:
            (xy,) = coll.get_offsets()
            points[coll.get_label()] = (tuple(np.round(xy, 6)), coll.get_facecolor())
        want = {arm: s for arm, s in table[family].items() if math.isfinite(s["excess_median"])}
        assert len(points) == len(want)  # a row without a success is not drawn
        for arm, s in want.items():
            label = arm.label + (" (bound)" if arm.method == "clairvoyant" else "")
            xy, face = points[label]
            assert xy == (round(100 * s["excess_median"], 6), round(100 * s["success"], 6))
            assert (face.size == 0 or face[0, 3] == 0) == (arm.method == "clairvoyant")


def test_the_lifelong_figure_plots_success_and_excess_per_block_of_tasks(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    from copi.reports import _lifelong as lr

    def row(task: int, outcome: str, excess: float | None) -> dict[str, Any]:
        return {"task": task, "outcome": outcome, "excess": excess, "unfamiliar": 0.1 * task}

    # 20 tasks, 2 per point: success 1, 0.5, 1, ... and excess medians per block
    rows = [row(t, "success" if t % 4 != 3 else "timeout", 0.01 * t) for t in range(20)]
    drawn = _caught(monkeypatch, "copi.reports._figures")
    lr._figure_lifelong({"copi-learnt": rows, "dwa": rows[:10]}, 20, tmp_path / "f.png")
    (fig,) = drawn
    ax_s, ax_e, ax_u = fig.axes[:3]
    blocks = [rows[i : i + 2] for i in range(0, 20, 2)]
    success = [100 * np.mean([r["outcome"] == "success" for r in b]) for b in blocks]
    excess = [100 * np.median([r["excess"] for r in b if r["outcome"] == "success"])
              for b in blocks]  # fmt: skip
    copi_s, dwa_s = ax_s.get_lines()[:2]
    assert list(copi_s.get_xdata()) == [1.5 + 2 * i for i in range(10)]
    np.testing.assert_allclose(copi_s.get_ydata(), success)
    np.testing.assert_allclose(dwa_s.get_ydata(), success[:5])  # only its 10 tasks
    np.testing.assert_allclose(ax_e.get_lines()[0].get_ydata(), excess)
    # unfamiliar readings: drawn for copi's methods only, the others keep their colour
    assert len(ax_u.get_lines()[0].get_ydata()) == 10 and len(ax_u.get_lines()[1].get_ydata()) == 0
    assert [t.get_text() for t in ax_u.get_legend().get_texts()] == ["copi-learnt", "dwa"]


def test_fig5_draws_each_games_pursuer_and_evader_paths(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    from copi.reports import _navigation as report
    from copi.world import random_world

    world = random_world(seed=1)

    def game(k: int, captured: bool) -> dict[str, Any]:
        rng = np.random.default_rng(k)
        return {"world": world.to_dict(), "traces": np.zeros((0, 0, 2)), "radii": [],
                "episode": k, "captured": captured,
                "pursuer": rng.uniform(0, 5, (6, 2)), "evader": rng.uniform(0, 5, (6, 2))}  # fmt: skip

    runs = {"capability-static": [game(0, True), game(1, False)],
            "capability-dynamic": [game(2, False)]}  # fmt: skip
    drawn = _caught(monkeypatch, "copi.reports._figures")
    assert report._fig5(runs, tmp_path) == tmp_path / "fig5_pursuit.png"
    (fig,) = drawn
    titled = {ax.get_title(): ax for ax in fig.axes}
    assert set(titled) == {"(i) game 0 — captured", "(i) game 1 — escaped",
                           "(ii) game 2 — escaped"}  # fmt: skip
    for name, games in runs.items():
        for g in games:
            ax = next(a for t, a in titled.items() if t.split()[2] == str(g["episode"]))
            lines = {tuple(np.round(ln.get_xydata().ravel(), 6)) for ln in ax.get_lines()}
            for who in ("pursuer", "evader"):
                assert tuple(np.round(np.asarray(g[who]).ravel(), 6)) in lines, (name, who)
    assert report._fig5({}, tmp_path) is None
