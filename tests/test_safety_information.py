"""The crowd safety-information benchmark (studies/safety_information.py) runs end to
end on a small case and reports what it says it reports."""

from __future__ import annotations

import json
from pathlib import Path

from studies import safety_information


def test_the_safety_information_benchmark_runs(learnt_caps: Path, tmp_path: Path) -> None:
    out = tmp_path / "si.json"
    code = safety_information.main(["--caps", str(learnt_caps), "--episodes", "3",
                                    "--futures", "2", "--workers", "1", "--out", str(out)])  # fmt: skip
    assert code == 0
    r = json.loads(out.read_text())
    assert r["states"] > 0 and 0.0 <= r["safe_share"] <= 1.0
    for key in ("network_auc", "oracle_auc"):
        assert r[key] is None or 0.0 <= r[key] <= 1.0
    for source in ("network", "oracle"):
        for guard in ("1.05", "0"):
            assert 0 <= r[f"successes_{source}_guard_{guard}"] <= 3
    # the oracle's knowledge taken apart, on the visited states only
    code = safety_information.main(["--caps", str(learnt_caps), "--episodes", "2",
                                    "--futures", "2", "--workers", "1", "--decompose",
                                    "--skip-choice", "--out", str(out)])  # fmt: skip
    r = json.loads(out.read_text())
    assert code == 0 and not any(k.startswith("successes") for k in r)
    for name in ("visible", "no_headings", "headings_within_a_turn"):
        v = r[f"oracle_auc_{name}"]
        assert v is None or 0.0 <= v <= 1.0


def test_the_visible_discs_are_the_ones_the_reading_changes_without() -> None:
    """A disc in front of the agent is seen; one behind it, on the same ray, is not."""

    from copi.world import Simulator, World

    world = World([[-10, -10], [10, -10], [10, 10], [-10, 10]])
    sim = Simulator(world, start=(0.0, 0.0), goal=(5.0, 5.0),
                    centers=[(3.0, 0.0), (6.0, 0.0), (0.0, -4.0)], radii=[0.5, 0.5, 0.5],
                    seed=0)  # fmt: skip
    assert safety_information._visible(sim).tolist() == [True, False, True]
