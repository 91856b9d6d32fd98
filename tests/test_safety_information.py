"""The crowd safety-information benchmark (benchmarks/safety_information.py) runs end to
end on a small case and reports what it says it reports."""

from __future__ import annotations

import json
from pathlib import Path

from benchmarks import safety_information


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
