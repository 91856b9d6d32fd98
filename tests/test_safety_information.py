"""The crowd safety-information benchmark (studies/safety_information.py) runs end to
end on a small case and reports what it says it reports."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
from studies import safety_information


def test_the_safety_information_benchmark_runs(learnt_caps: Path, tmp_path: Path) -> None:
    out = tmp_path / "si.json"
    code = safety_information.main(["--caps", str(learnt_caps), "--episodes", "3",
                                    "--futures", "2", "--workers", "1", "--out", str(out)])  # fmt: skip
    assert code == 0
    r = json.loads(out.read_text())
    assert r["states"] > 0 and 0.0 < r["safe_share"] < 1.0
    # Each AUC says which way it points: P(safe) ranks the safe probes above the unsafe
    # ones, well above chance (0.5; with a few hundred unsafe probes chance spreads about
    # 0.02), and the oracle, who knows the true present and the motion model, above the
    # network, who sees only the reading: an AUC inverted (1 - AUC, or scores of the wrong
    # sign) is below 0.5 and fails here.
    assert r["network_auc"] > 0.6, r
    assert r["oracle_auc"] > r["network_auc"], r
    for source in ("network", "oracle"):
        for guard in ("1.05", "0"):
            assert 0 <= r[f"successes_{source}_guard_{guard}"] <= 3
    # the oracle's knowledge taken apart, on the visited states only
    code = safety_information.main(["--caps", str(learnt_caps), "--episodes", "2",
                                    "--futures", "2", "--workers", "1", "--decompose",
                                    "--skip-choice", "--out", str(out)])  # fmt: skip
    r = json.loads(out.read_text())
    assert code == 0 and not any(k.startswith("successes") for k in r)
    for name in ("visible", "no_headings", "headings_within_a_turn"):  # less knowledge, yet
        assert 0.6 < r[f"oracle_auc_{name}"] <= 1.0, (name, r)  # well above chance


def test_the_oracle_s_probability_is_that_of_a_safe_move() -> None:
    """By hand: a disc just ahead along +x, nothing else near. Every future's probe of
    the move into it collides, so the oracle's P(safe) of that move is 0; the move away
    from it leaves the disc behind in every future, so its P(safe) is 1."""
    from copi.world import Simulator, World

    world = World([[0, 0], [20, 0], [20, 20], [0, 20]])
    sim = Simulator(world, start=(10.0, 10.0), goal=(2.0, 2.0), centers=[(10.9, 10.0)],
                    radii=[0.5], seed=0)  # fmt: skip
    unit, actions, _ = safety_information._moves()
    assert np.allclose(unit[0], [1, 0]) and np.allclose(unit[8], [-1, 0])
    p = safety_information._oracle_p(sim, (0, 0), 8)
    assert p.shape == (len(actions),) and p[0] == 0.0 and p[8] == 1.0, p


def test_the_visible_discs_are_the_ones_the_reading_changes_without() -> None:
    """A disc in front of the agent is seen; one behind it, on the same ray, is not."""

    from copi.world import Simulator, World

    world = World([[-10, -10], [10, -10], [10, 10], [-10, 10]])
    sim = Simulator(world, start=(0.0, 0.0), goal=(5.0, 5.0),
                    centers=[(3.0, 0.0), (6.0, 0.0), (0.0, -4.0)], radii=[0.5, 0.5, 0.5],
                    seed=0)  # fmt: skip
    assert safety_information._visible(sim).tolist() == [True, False, True]
