from __future__ import annotations

import sqlite3
from pathlib import Path

import numpy as np
import pytest

from copi.experiments.benchmark import BenchmarkConfig, benchmark_max_steps, run_benchmark
from copi.learning import LearnParams, learn
from copi.methods import MethodRun, parse_methods
from copi.reports import write_benchmark_report
from copi.results import ResultsStore, paired_difference
from tests.cli.test_main import run

TIMINGS = {"decision_us", "strategy_us"}


def test_paired_difference_against_a_hand_computed_case() -> None:
    # Success of A and B on five episodes: A wins 2, loses 0: +40 points.
    a = [1, 1, 1, 0, 1]
    b = [1, 0, 1, 0, 0]
    d = paired_difference(a, b, resamples=4000, seed=1)
    assert d.estimate == pytest.approx(0.4) and d.n == 5
    # The bootstrap of a mean of differences in {0, 1}: the interval is within [0, 1]
    # and holds the estimate; with the differences all equal it is that value exactly.
    assert 0.0 <= d.low <= 0.4 <= d.high <= 1.0
    same = paired_difference([3.0, 4.0, 5.0], [2.0, 3.0, 4.0])
    assert (same.estimate, same.low, same.high) == pytest.approx((1.0, 1.0, 1.0))
    assert same.excludes_zero
    # Medians: A = [1, 2, 10], B = [0, 0, 0] -> median difference 2.
    med = paired_difference([1.0, 2.0, 10.0], [0.0, 0.0, 0.0], statistic="median")
    assert med.estimate == 2.0 and med.low >= 1.0 and med.high <= 10.0
    # Large sample: the percentile interval agrees with the normal one (1.96 s / sqrt n).
    rng = np.random.default_rng(0)
    x = rng.random(4000) < 0.7
    y = rng.random(4000) < 0.6
    d = paired_difference(x, y, resamples=2000)
    diff = x.astype(float) - y.astype(float)
    half = 1.96 * diff.std(ddof=1) / np.sqrt(len(diff))
    assert d.low == pytest.approx(diff.mean() - half, abs=0.004)
    assert d.high == pytest.approx(diff.mean() + half, abs=0.004)
    assert not paired_difference([0, 1], [1, 0]).excludes_zero
    with pytest.raises(ValueError, match="paired samples"):
        paired_difference([1, 2], [1])


def test_step_limit() -> None:
    assert benchmark_max_steps(10.0) == 130
    assert benchmark_max_steps(float("nan")) == 1000
    assert benchmark_max_steps(500.0) == 1000


def test_parse_methods() -> None:
    assert parse_methods("dwa") == [MethodRun("dwa", "sensor", "greedy"),
                                    MethodRun("dwa", "map", "route")]  # fmt: skip
    assert parse_methods("copi-extended@map,replan") == [
        MethodRun("copi-extended", "map", "route"),
        MethodRun("replan", "oracle", "route"),
    ]
    assert parse_methods("dwa@sensor:mapping,dwa", strategy="causal") == [
        MethodRun("dwa", "sensor", "causal"), MethodRun("dwa", "sensor", "mapping"),
        MethodRun("dwa", "map", "route"),
    ]  # fmt: skip
    with pytest.raises(ValueError, match="replan needs sensing level 'oracle' or above"):
        parse_methods("replan@sensor")
    with pytest.raises(ValueError, match="a global strategy is chosen at level sensor only"):
        parse_methods("dwa@map:mapping")
    with pytest.raises(ValueError, match=r"got 'copi-learnt\+priors' \(now 'copi-learnt-priors'\)"):
        parse_methods("copi-learnt+priors")


@pytest.fixture(scope="module")
def caps(tmp_path_factory: pytest.TempPathFactory) -> dict[str, str]:
    d = tmp_path_factory.mktemp("caps")
    out = {}
    for preset, directions in (("extended", 16),):
        path = d / f"capabilities-{preset}.npz"
        learn(LearnParams(worlds=12, steps=200, seed=1, directions=directions)).save(path)
        out[preset] = str(path)
    return out


def _rows(path: Path) -> list[dict]:
    with ResultsStore(path) as store:
        return [
            {k: v for k, v in r.items() if k not in TIMINGS}
            for r in sorted(store.episodes(), key=lambda r: (r["run_id"], r["episode"]))
        ]


def test_every_method_meets_the_same_episodes_and_runs_resume(
    caps: dict[str, str], tmp_path: Path
) -> None:
    methods = tuple(parse_methods("copi-extended@map,straight@map,compass-guard@sensor"))
    cfg = BenchmarkConfig(methods=methods, families=("star", "indoor"), episodes=4,
                          capabilities=caps)  # fmt: skip
    out = tmp_path / "b.sqlite"
    runs = run_benchmark(cfg, out, workers=1)
    assert len(runs) == 6
    rows = _rows(out)
    assert len(rows) == 24
    by = {}
    for r in rows:
        by.setdefault((r["family"], r["episode"]), []).append(r)
        assert r["outcome"] in ("success", "collision", "timeout")
        assert r["success"] + r["collided"] + r["timed_out"] == 1
        if r["success"]:
            assert r["excess"] >= 0.0
    for group in by.values():  # one world and one optimum per episode, whatever the method
        assert len({r["world"] for r in group}) == 1
        assert len({r["optimal_length"] for r in group}) == 1
    # Interrupted: lose some rows; rerun (with two workers) -> the same table.
    with sqlite3.connect(out) as db:
        db.execute("DELETE FROM episodes WHERE episode >= 2 AND method = 'straight'")
    run_benchmark(cfg, out, workers=2)
    assert _rows(out) == rows
    # A longer run extends the shorter one (episodes are not part of a run's identity).
    longer = BenchmarkConfig(methods=methods, families=("star",), episodes=6, capabilities=caps)
    run_benchmark(longer, out, workers=1)
    assert len(_rows(out)) == 24 + 3 * 2
    report = write_benchmark_report(out, tmp_path / "rep")
    text = report.read_text()
    assert "## star (6 episodes)" in text and "## indoor (4 episodes)" in text
    assert "| compass-guard | sensor | greedy | 6 |" in text
    assert (tmp_path / "rep" / "benchmark_success_excess.png").stat().st_size > 10_000
    # the overview's cells are the family tables' success and median excess, row by row
    overview = text.split("## Overview")[1].split("### Δ success")[0]
    cells = {tuple(c.strip() for c in ln.strip("|").split("|")[:3]): ln.strip("|").split("|")[3:]
             for ln in overview.splitlines() if ln.startswith("| ") and "---" not in ln
             and not ln.startswith("| method")}  # fmt: skip
    assert cells
    for family, col in (("star", 0), ("indoor", 1)):
        table = text.split(f"## {family} (")[1].split("\n## ")[0]
        for ln in table.splitlines():
            parts = [c.strip() for c in ln.strip("|").split("|")]
            if len(parts) < 8 or parts[0] in ("method", "---") or parts[0].startswith("---"):
                continue
            success = parts[4].removesuffix(" %")
            excess = parts[7].removesuffix(" %")
            cell = cells[tuple(parts[:3])][col].strip()
            assert cell.split()[0] == success, (family, parts[:3], cell)
            if excess != "—":
                assert cell.endswith(f"({float(excess):.0f})"), (family, parts[:3], cell)


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--families", "moon"], "family must be one of crowd, indoor, maps, polygon, star"),
        (["--methods", "astar"], "method must be one of copi-faithful"),
        (["--methods", "replan@map"], "replan needs sensing level 'oracle' or above"),
        (["--methods", "dwa@psychic"], "sensing level must be one of sensor, map, oracle"),
        (["--sensor-strategy", "astar"], "sensor strategy must be one of greedy, mapping"),
    ],
)
def test_benchmark_bad_input_writes_nothing(
    args: list[str], message: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    code, _, err = run(["benchmark", "-o", str(tmp_path / "b"), *args], capsys)
    assert code == 2 and message in err and "Traceback" not in err, err
    assert not (tmp_path / "b").exists()


def test_benchmark_without_navground(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    import sys

    monkeypatch.setitem(sys.modules, "navground", None)
    monkeypatch.setitem(sys.modules, "navground.core", None)
    code, _, err = run(
        ["benchmark", "-o", str(tmp_path / "b"), "--methods", "navground-hl"], capsys
    )
    assert code == 2 and "navground-hl needs navground, which is not installed" in err
    assert not (tmp_path / "b").exists()
    code, out, err = run(
        ["benchmark", "-o", str(tmp_path / "c"), "--methods", "straight@map,dwa@map",
         "--families", "star", "--episodes", "2", "--workers", "1"],
        capsys,
    )  # fmt: skip
    assert code == 0, err
    # no copi-learnt here: the reference is the first method run, and the report says so
    assert "**Reference: straight** (the first method of the run" in out
    assert "| **straight** | map | route | 2 |" in out and "| dwa | map | route | 2 |" in out
    # --against names a method of this run or one the store already holds; any other is
    # refused before anything runs
    more = ["benchmark", "-o", str(tmp_path / "c"), "--families", "star", "--episodes", "2",
            "--workers", "1"]  # fmt: skip
    code, out, err = run([*more, "--methods", "compass-guard@map", "--against", "dwa"], capsys)
    assert code == 0, err
    assert "**Reference: dwa** (named with --against)" in out
    code, _, err = run([*more, "--methods", "vfh@map", "--against", "tangent-bug"], capsys)
    assert code == 2 and "--against tangent-bug: it is not among the methods run (vfh) nor " \
        "among those the store holds" in err, err  # fmt: skip


def test_a_mapping_run_is_its_own_run(tmp_path: Path) -> None:
    greedy = parse_methods("compass-guard@sensor,compass-guard@map")
    mapping = parse_methods("compass-guard@sensor,compass-guard@map", strategy="mapping")
    assert greedy[1] == mapping[1]  # the map level follows the route either way
    both = BenchmarkConfig(methods=(*greedy, mapping[0]), families=("indoor",), episodes=2)
    assert both.run_id("indoor", greedy[0]) != both.run_id("indoor", mapping[0])
    run_benchmark(both, tmp_path / "m.sqlite")
    text = write_benchmark_report(tmp_path / "m.sqlite", tmp_path / "rep").read_text()
    assert "*mapping* (a map built from the ranges, re-planned)" in text
    assert "| **compass-guard** | sensor | greedy | 2 |" in text
    assert "| **compass-guard** | sensor | mapping | 2 |" in text
    # a strategy no older report knew is reported as the others are
    causal = BenchmarkConfig(methods=tuple(parse_methods("compass-guard@sensor:causal")),
                             families=("indoor",), episodes=1)  # fmt: skip
    run_benchmark(causal, tmp_path / "m.sqlite")
    text = write_benchmark_report(tmp_path / "m.sqlite", tmp_path / "rep").read_text()
    assert "| **compass-guard** | sensor | causal | 1 |" in text


def test_stale_capabilities_are_refused_not_reused(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A directory's capabilities learnt with seed 0 are not taken for a seed-1 run (as
    `reproduce -o D --seed 1` and `benchmark` once did), and are left as they were."""
    import dataclasses

    import copi.experiments.benchmark as bm
    from copi.errors import InvalidArgumentError
    from copi.learning import LearnParams
    from copi.methods import PRESETS

    def learns(params: LearnParams) -> None:
        monkeypatch.setitem(PRESETS, "faithful", dataclasses.replace(PRESETS["faithful"],
                                                                     learn=params))  # fmt: skip

    learns(LearnParams(worlds=4, steps=80, directions=4))
    path = Path(bm.ensure_capabilities(tmp_path, {"faithful"}, seed=0)["faithful"])
    before = path.read_bytes()
    assert bm.ensure_capabilities(tmp_path, {"faithful"}, seed=0)["faithful"] == str(path)
    with pytest.raises(InvalidArgumentError, match="learnt with seed=0, not 1"):
        bm.ensure_capabilities(tmp_path, {"faithful"}, seed=1)
    learns(LearnParams(worlds=5, steps=80))
    with pytest.raises(InvalidArgumentError, match="learnt with worlds=4, not 5"):
        bm.ensure_capabilities(tmp_path, {"faithful"}, seed=0)
    assert path.read_bytes() == before


def test_intervals_are_printed_for_what_they_are() -> None:
    from copi.results import format_difference

    spread = paired_difference([1, 0, 1, 1, 0, 1, 1, 1, 0, 1, 1, 1], [0] * 12)
    assert format_difference(spread).startswith("+75.0 [") and "alike" not in format_difference(spread)
    # every pair differs by the same amount: no spread to show, and the table says so
    alike = paired_difference([1] * 12, [0] * 12)
    assert format_difference(alike) == "+100.0 (all 12 pairs alike)"
    few = paired_difference([1, 0], [0, 0])
    assert format_difference(few) == "+50.0 (n = 2, no interval)"
    assert format_difference(paired_difference([], [])) == "—"


def test_the_report_table_is_the_store(tmp_path: Path) -> None:
    """Every success, collision and timeout cell of the report is the share of the stored
    rows it says, and each Δ success the paired difference computed from those rows."""
    import re

    from copi.reports import read_benchmark

    methods = tuple(parse_methods("straight@map,compass-guard@map,dwa@map"))
    cfg = BenchmarkConfig(methods=methods, families=("crowd",), episodes=12)
    run_benchmark(cfg, tmp_path / "b.sqlite", workers=1)
    text = write_benchmark_report(tmp_path / "b.sqlite", tmp_path / "rep").read_text()
    groups, _, _ = read_benchmark(tmp_path / "b.sqlite")
    rows = {arm.method: r for arm, r in groups["crowd"].items()}
    ref = {int(r["episode"]): r["outcome"] == "success" for r in rows["straight"]}
    checked = 0
    for line in text.splitlines():
        m = re.match(r"\| \**([a-z-]+)\** \| map \| route \| (\d+) \| ([\d.]+) % \| ([\d.]+) % \| "
                     r"([\d.]+) % \|", line)  # fmt: skip
        if not m or m.group(1) not in rows:
            continue
        got = rows[m.group(1)]
        n = len(got)
        share = {o: 100 * sum(r["outcome"] == o for r in got) / n
                 for o in ("success", "collision", "timeout")}  # fmt: skip
        assert int(m.group(2)) == n == 12
        assert [float(m.group(k)) for k in (3, 4, 5)] == [
            round(share[o], 1) for o in ("success", "collision", "timeout")]
        if m.group(1) != "straight":  # paired against the first method run
            won = {int(r["episode"]): r["outcome"] == "success" for r in got}
            d = paired_difference([won[k] for k in sorted(ref)], [ref[k] for k in sorted(ref)])
            assert f"{round(100 * d.estimate, 1) + 0.0:+.1f} [" in line
        checked += 1
    assert checked == 3, text
    # one family: its words are there too (a world file's page quotes them), and a
    # report paired with another method speaks of that method
    words = text.split("### Method by method")[1].split("\n## ")[0]
    assert "**compass-guard** at map (route): " in words and "**dwa** at map" in words
    other = write_benchmark_report(tmp_path / "b.sqlite", tmp_path / "rep2",
                                   against="dwa").read_text()  # fmt: skip
    assert "**compass-guard** at map (route): more successes than dwa in " in other
