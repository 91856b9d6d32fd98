"""How much the landmarks depend on the seed: copi's rule (the median over bootstrap maps of
the knee of H(k)) beside the rule of copi 0.2 (the knee of the map's own H(k)) and the
paper's literal one (maximum curvature), paper §II-B.

    python studies/landmarks.py --seeds 10 --workers 2 [--out docs/landmarks.md]

Three studies with the defaults of ``copi learn --preset faithful`` (100 worlds x 300
steps, two GNG passes, the paper's setup): whole pipelines over seeds 0..n-1, map seeds on
the readings of exploration seed 0, and exploration seeds under map seed 0. Each seed is
learnt once (copi's rule); the other rules read their k from the same map's H(k), and
their templates come from the same symmetry reduction, so every rule is compared on the
same maps. Prints the landmark and template counts per seed and max / min per study.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

from copi.learning import (
    LearnParams,
    SymmetryGroup,
    learn,
    reduce_landmarks,
    ring_operators,
    skeletonize,
)

STUDIES = {
    "whole pipeline (seed s)": lambda s: {"seed": s},
    "map seeds (readings of seed 0)": lambda s: {"seed": 0, "map_seed": s},
    "exploration seeds (map seed 0)": lambda s: {"seed": s, "map_seed": 0},
}
RULES = {"copi (median of bootstrap knees)": None, "0.2 (the map's knee)": "knee",
         "literal (maximum curvature)": "curvature"}  # fmt: skip


def _counts(caps, method: str | None) -> tuple[int, int]:  # type: ignore[no-untyped-def]
    """(landmarks, templates) of ``caps`` under rule ``method`` (None: as learnt)."""
    if method is None:
        return caps.landmarks.n_landmarks, len(caps.reduction.templates)
    lm = skeletonize((caps.nodes, caps.edges), method=method)
    group = SymmetryGroup.generate(ring_operators(caps.n_rays))
    sizes = np.bincount(lm.members, minlength=lm.n_landmarks)
    red = reduce_landmarks(lm.points, group, tol=caps.stats["symmetry_tolerance"],
                           order=np.argsort(-sizes, kind="stable"))  # fmt: skip
    return lm.n_landmarks, len(red.templates)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--seeds", type=int, default=10)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--out", default=None, help="write the tables here (Markdown)")
    a = ap.parse_args()
    t0 = time.perf_counter()
    lines = [
        f"# Landmarks over {a.seeds} seeds (`python studies/landmarks.py --seeds {a.seeds}`)",
        "",
        "<!-- generated: written whole by studies/landmarks.py -->",
        "",
        "Counts as landmarks (templates). The defaults of `copi learn --preset faithful`: "
        "100 worlds x 300 steps, the paper's setup (the paper: 593 nodes, 9 landmarks).",
        "",
    ]
    seconds = []
    learnt: dict[tuple[str, int], object] = {}
    for study, params in STUDIES.items():
        for s in range(a.seeds):
            key = tuple(sorted(params(s).items()))
            if key not in learnt:
                print(f"\r{study}: seed {s + 1}/{a.seeds}   ", end="", file=sys.stderr, flush=True)
                t1 = time.perf_counter()
                learnt[key] = learn(LearnParams(directions=4, workers=a.workers, **params(s)))
                seconds.append(time.perf_counter() - t1)
            learnt[(study, s)] = learnt[key]
    print(file=sys.stderr)
    for study in STUDIES:
        lines += [f"## {study}", "",
                  "| rule | per seed | landmarks max / min | templates max / min |",
                  "|---|---|---|---|"]  # fmt: skip
        nodes = []
        for rule, method in RULES.items():
            got = [_counts(learnt[(study, s)], method) for s in range(a.seeds)]
            lm = [g[0] for g in got]
            tm = [g[1] for g in got]
            shown = ", ".join(f"{x} ({y})" for x, y in got)
            lines.append(f"| {rule} | {shown} | {max(lm) / max(min(lm), 1):.2f} | "
                         f"{max(tm) / max(min(tm), 1):.2f} |")  # fmt: skip
        nodes = [learnt[(study, s)].nodes.shape[0] for s in range(a.seeds)]  # type: ignore[attr-defined]
        lines += ["", f"Map nodes: {', '.join(map(str, nodes))}.", ""]
    lines.append(
        f"Learning one seed took {np.median(seconds):.1f} s (median, {a.workers} workers); all "
        f"{len(seconds)} in {time.perf_counter() - t0:.0f} s."
    )
    text = "\n".join(lines) + "\n"
    print(text)
    if a.out:
        Path(a.out).write_text(text, encoding="utf-8")


if __name__ == "__main__":
    main()
