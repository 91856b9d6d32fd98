"""Every family measured against what is possible: the clairvoyant bound and the
model-predictive oracle beside every method, on the same episodes.

    python studies/ceilings.py --bench results/ceilings --episodes 200 \\
        --oracle-episodes 200 --out docs/ceilings.md

Runs ``copi benchmark`` three times into one directory (resumable): every default method
and ``clairvoyant`` on ``--episodes`` episodes per family, then ``model-oracle`` (0.1-0.3 s
an episode, median), then the planners at level map (``tracked-mpc``, ``copi-predictive``
and its ablations) on
the first ``--oracle-episodes``; the report pairs each row on the episodes both ran.
Writes a summary: per family and level, the share solvable at all (the clairvoyant,
the one bound), the reference planner (model-oracle: called a bound in a family only
where it is at or above every method), the best method and copi's, the gap from each to
what is solvable, and the reference planner against each method (paired, 95 %
intervals). A share of a gap closed is claimed only where both the gap and copi's part
of it exclude zero.
"""

from __future__ import annotations

import argparse
import math
import subprocess
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from studies._common import kept_times  # noqa: E402

METHODS = ["copi-learnt", "copi-extended", "copi-faithful", "compass-guard", "straight", "vfh",
           "dwa", "tangent-bug", "replan", "navground-hrvo", "navground-hl",
           "clairvoyant"]  # fmt: skip
FAMILIES = ("star", "polygon", "indoor", "maps", "crowd")


def _bench(bench: Path, episodes: int, methods: list[str], workers: int) -> None:
    # the report pairs every row with copi-learnt when the store holds it (the default)
    against = ["--against", "copi-learnt"] if "copi-learnt" in methods else []
    subprocess.run([sys.executable, "-m", "copi", "benchmark", "-o", str(bench),
                    "--episodes", str(episodes), "--methods", ",".join(methods),
                    "--workers", str(workers), *against], check=True)  # fmt: skip


def _pct(x: float) -> str:
    return "—" if not math.isfinite(x) else f"{100 * x:.1f} %"


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--bench", default="results/ceilings")
    ap.add_argument("--episodes", type=int, default=200)
    ap.add_argument("--oracle-episodes", type=int, default=200)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--out", default="docs/ceilings.md")
    a = ap.parse_args()
    from copi.reports import read_benchmark
    from copi.results import paired_difference

    bench = Path(a.bench)
    from copi.methods import method_spec

    methods = [m for m in METHODS if method_spec(m).available()]
    # wall times of the runs that did the work (a rerun that only resumes keeps them)
    measured = {}
    # the planners at level map, copi-predictive's ablations among them (what the
    # contexts and the safety network add, on the same episodes)
    planners = ["tracked-mpc", "copi-predictive", "copi-predictive-contexts",
                "copi-predictive-nonet"]
    for key, eps, ms in (("methods", a.episodes, methods),
                         ("oracle", a.oracle_episodes, ["model-oracle"]),
                         ("tracked", a.oracle_episodes, planners)):  # fmt: skip
        t0 = time.perf_counter()
        _bench(bench, eps, ms, a.workers)
        took = time.perf_counter() - t0
        measured[key] = (took, {"seconds": round(took), "workers": a.workers})
    timing = kept_times(bench / "ceilings-timing.json", measured)
    groups, _, _ = read_benchmark(bench / "benchmark.sqlite")
    lines = [
        "# Ceilings: every family against what is possible",
        "",
        "<!-- generated: written whole by studies/ceilings.py -->",
        "",
        f"`python studies/ceilings.py --bench {a.bench} --episodes {a.episodes} "
        f"--oracle-episodes {a.oracle_episodes}` (benchmark seed 0; "
        f"{timing['methods']['seconds'] / 60:.0f} min for the methods and the clairvoyant, "
        f"{timing['oracle']['seconds'] / 60:.0f} min for the oracle, "
        f"{timing['tracked']['seconds'] / 60:.0f} min for the planners at level map (tracked-mpc, "
        "copi-predictive and its two ablations), "
        f"{timing['oracle']['workers']} worker(s)). *clairvoyant* knows the obstacles' "
        "whole future (they ignore the agent, "
        "so it can be recorded) and replays its space-time plan through the simulator: the "
        "share of episodes solvable at all: a bound. *model-oracle* knows the present "
        "(positions and velocities) and the obstacles' motion model (their random walk's "
        "true parameters), not the future: a reference planner, a bound of a family only "
        "where it is at or above every method (the last column says where). *tracked-mpc* "
        "and *copi-predictive* are methods: the oracle's planner at level map, on the discs "
        "they make out in their reading, with a motion model estimated from their own tracks "
        "(tracked-mpc, hand-set priors) or learnt once from task-free walks "
        "(copi-predictive). Each row over the first "
        f"{a.oracle_episodes} episodes of a family (those the oracle ran), so that every "
        "cell is paired; Δ in points with 95 % bootstrap intervals.",
        "",
        "| family | solvable (clairvoyant) | model-oracle | best method (level) | "
        "copi-learnt map / sensor | copi-predictive | gap best → solvable | "
        "oracle − best method | oracle beats | oracle a bound here |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    detail = [
        "",
        "## The oracle against every method (same episodes)",
        "",
        "| family | method (level) | success | oracle − method |",
        "|---|---|---|---|",
    ]
    paragraphs: list[str] = []
    weak_oracle: list[str] = []
    for fam in FAMILIES:
        arms = groups.get(fam, {})
        oracle = next((rows for arm, rows in arms.items() if arm.method == "model-oracle"), None)
        if oracle is None:
            continue
        keep = {int(r["episode"]) for r in oracle if r["outcome"] != "skipped"}

        def won(rows: list, keep: set[int] = keep) -> dict[int, bool]:
            return {int(r["episode"]): r["outcome"] == "success" for r in rows
                    if r["outcome"] != "skipped" and int(r["episode"]) in keep}  # fmt: skip

        o = won(oracle)
        rate = {}
        for arm, rows in arms.items():
            w = won(rows)
            if w:
                rate[arm] = (sum(w.values()) / len(w), w)
        clair = next((v for arm, v in rate.items() if arm.method == "clairvoyant"), None)
        # every method but the bound and the reference planner itself (its rows are o)
        methods_only = {arm: v for arm, v in rate.items()
                        if not method_spec(arm.method).bound
                        and arm.method != "model-oracle"}  # fmt: skip
        best_arm = max(methods_only, key=lambda arm: methods_only[arm][0])
        beats = 0
        at_or_above = True  # no method's success above the oracle's on the same episodes
        for arm, (r, w) in sorted(methods_only.items(), key=lambda kv: -kv[1][0]):
            common = sorted(set(o) & set(w))
            d = paired_difference([o[k] for k in common], [w[k] for k in common])
            beats += d.excludes_zero and d.estimate > 0
            at_or_above &= d.estimate >= 0
            detail.append(
                f"| {fam} | {arm.method} ({arm.sensing}) | {_pct(r)} | "
                f"{100 * d.estimate:+.1f} [{100 * d.low:+.1f}, {100 * d.high:+.1f}] |"
            )
        b_rate, b_w = methods_only[best_arm]
        common = sorted(set(o) & set(b_w))
        d = paired_difference([o[k] for k in common], [b_w[k] for k in common])
        cl = {arm.sensing: v[0] for arm, v in methods_only.items() if arm.method == "copi-learnt"}
        solvable = clair[0] if clair else math.nan
        o_rate = sum(o.values()) / len(o)
        if not (d.excludes_zero and d.estimate > 0):
            weak_oracle.append(fam)
        baselines = {arm: v for arm, v in methods_only.items()
                     if not arm.method.startswith("copi")}  # fmt: skip
        base_arm = max(baselines, key=lambda arm: baselines[arm][0])
        base_rate = baselines[base_arm][0]
        copi_map = cl_map = next((v for arm, v in methods_only.items()
                                  if arm.method == "copi-learnt" and arm.sensing == "map"),
                                 None)  # fmt: skip
        if copi_map is not None:
            gap = o_rate - base_rate
            common = sorted(set(cl_map[1]) & set(baselines[base_arm][1]))
            dd = paired_difference([cl_map[1][k] for k in common],
                                   [baselines[base_arm][1][k] for k in common])  # fmt: skip
            common = sorted(set(o) & set(baselines[base_arm][1]))
            dg = paired_difference([o[k] for k in common],
                                   [baselines[base_arm][1][k] for k in common])  # fmt: skip
            if dg.excludes_zero and dg.estimate > 0 and dd.excludes_zero:
                share = f"closes {100 * (copi_map[0] - base_rate) / gap:.0f} % of that gap"
            elif not (dg.excludes_zero and dg.estimate > 0):
                share = ("has no measurable gap to close (the oracle's lead over that baseline "
                         f"is {100 * dg.estimate:+.1f} [{100 * dg.low:+.1f}, "
                         f"{100 * dg.high:+.1f}], an interval holding 0)")  # fmt: skip
            else:
                share = ("is within noise of that baseline (an interval holding 0): no share "
                         "of the gap is claimed")  # fmt: skip
            paragraphs.append(
                f"**{fam}**: {_pct(solvable)} of the episodes are solvable at all; the "
                f"model-predictive oracle succeeds in {_pct(o_rate)}, the best baseline "
                f"({base_arm.method} at {base_arm.sensing}) in {_pct(base_rate)}. "
                f"copi-learnt at map succeeds in {_pct(copi_map[0])} "
                f"({100 * dd.estimate:+.1f} [{100 * dd.low:+.1f}, {100 * dd.high:+.1f}] "
                f"points against that baseline): it {share}."
            )
        pred = next((v[0] for arm, v in methods_only.items()
                     if arm.method == "copi-predictive"), math.nan)  # fmt: skip
        lines.append(
            f"| {fam} | {_pct(solvable)} | {_pct(sum(o.values()) / len(o))} | {best_arm.method} "
            f"({best_arm.sensing}) {_pct(b_rate)} | {_pct(cl.get('map', math.nan))} / "
            f"{_pct(cl.get('sensor', math.nan))} | {_pct(pred)} | "
            f"{100 * (solvable - b_rate):+.1f} | "
            f"{100 * d.estimate:+.1f} [{100 * d.low:+.1f}, {100 * d.high:+.1f}] | "
            f"{beats} of {len(methods_only)} rows | {'yes' if at_or_above else 'no'} |"
        )
    out = Path(a.out)
    gaps = ["", "## How much of the gap copi closes", "",
            "The gap is the oracle's success minus the best baseline's (the hand-written "
            "methods and peers, at any level); copi-learnt's share of it is (copi-learnt "
            "at map − best baseline) / gap, claimed only where the gap and copi-learnt's "
            "difference from that baseline both have intervals excluding zero.", ""]  # fmt: skip
    if weak_oracle:
        gaps += [f"In {', '.join(weak_oracle)} the oracle does no better than the best method "
                 "measurably (paired interval holding 0 or below): there, even where no method's "
                 "point estimate is above it (the last column of the first table), it is "
                 "no measurable ceiling — it is a first model-predictive controller, not "
                 "the best an agent that knows the present and the motion model could do — "
                 "and only the clairvoyant's share bounds what is possible.", ""]  # fmt: skip
    out.write_text("\n".join(lines + gaps + ["\n\n".join(paragraphs)] + detail) + "\n")
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
