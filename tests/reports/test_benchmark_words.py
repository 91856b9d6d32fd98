"""The benchmark report's words on its tables are read from the paired differences: a
row is "more" or "fewer" only where its interval excludes zero, never by its estimate
alone (the analysis pages quote these words instead of comparing by hand)."""

from __future__ import annotations

from copi.methods import MethodRun
from copi.reports._benchmark import _said
from copi.results import PairedDifference


def _pair(estimate: float, low: float, high: float, n: int = 200):
    d = PairedDifference(estimate, low, high, n)
    return d, d


def test_the_words_follow_the_intervals_not_the_estimates() -> None:
    ref = MethodRun("copi-learnt", "map", "route")
    guard = MethodRun("compass-guard", "map", "route")
    dwa = MethodRun("dwa", "map", "route")
    table = {
        "star": {ref: {"success": 0.90}, guard: {"success": 0.95}, dwa: {"success": 0.80}},
        "crowd": {ref: {"success": 0.40}, guard: {"success": 0.47}, dwa: {"success": 0.39}},
    }
    diffs = {
        # star: the guard's +5 holds zero (level), DWA's -10 does not (fewer)
        "star": {ref: None, guard: _pair(0.05, -0.01, 0.11), dwa: _pair(-0.10, -0.16, -0.04)},
        # crowd: the guard's +7 excludes zero (more); DWA's on too few pairs
        "crowd": {ref: None, guard: _pair(0.07, 0.01, 0.13), dwa: _pair(-0.2, -0.3, -0.1, n=5)},
    }
    text = "\n".join(_said(["star", "crowd"], table, diffs, "copi-learnt"))
    families, methods = text.split("### Method by method")
    assert "**star**: most successes compass-guard at map (95.0 %)" in families
    star = families.split("**star**")[1].split("**crowd**")[0]
    assert "more than copi-learnt: none" in star and "fewer: dwa (map, -10.0" in star
    crowd = families.split("**crowd**")[1]
    assert "more than copi-learnt: compass-guard (map, +7.0" in crowd and "fewer: none" in crowd
    paragraphs = {p.split("**")[1]: p for p in methods.split("\n\n") if p.startswith("**")}
    assert set(paragraphs) == {"compass-guard", "dwa"}  # the reference has no words of its own
    assert "more successes than copi-learnt in crowd (+7.0" in paragraphs["compass-guard"]
    assert "level (the interval holds zero) in star" in paragraphs["compass-guard"]
    assert "fewer in star (-10.0" in paragraphs["dwa"]
    assert "too few paired episodes in crowd" in paragraphs["dwa"]
