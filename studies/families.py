"""Statistics and pictures of the world families (docs/families.md).

    PYTHONPATH=src python studies/families.py --n 200 --seed 0 --pictures docs

prints the Markdown table of docs/families.md (``family_stats`` over n tasks per family;
``--into docs/families.md`` writes it between the page's ``<!-- table -->`` marks)
and, with ``--pictures DIR``, writes ``DIR/family_<name>.png``: worlds 0 to 3 of each family
for the seed, with the task and the obstacles that ``Simulator.from_world`` draws. Add
``--n 0`` for the pictures alone.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from copi.planning import FamilyStats, family_stats  # noqa: E402
from copi.world import FAMILIES, Simulator, draw_simulator, sample_world  # noqa: E402


def table(stats: list[FamilyStats]) -> str:
    head = (
        "| family | goal in sight | optimal / straight: median | p10 | p90 "
        "| mean free width | ms per world | unreachable |\n"
        "|---|---|---|---|---|---|---|---|\n"
    )
    rows = [
        f"| {s.family} | {100 * s.sight_share:.1f} % | {s.detour_median:.3f} | "
        f"{s.detour_p10:.3f} | {s.detour_p90:.3f} | {s.mean_free_width:.1f} | "
        f"{s.ms_per_world:.1f} | {s.unreachable} |"
        for s in stats
    ]
    return head + "\n".join(rows)


def pictures(directory: Path, seed: int, count: int = 4) -> list[Path]:
    """One row of ``count`` worlds per family: walls, start (red disc), goal (green star)
    and the obstacles drawn by ``Simulator.from_world`` (blue), titled by name."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    directory.mkdir(parents=True, exist_ok=True)
    written = []
    for family in FAMILIES:
        fig = Figure(figsize=(3.2 * count, 4.0), dpi=90)
        FigureCanvasAgg(fig)
        for k in range(count):
            rng = np.random.default_rng([seed, k])
            world = sample_world(family, rng)
            sim = Simulator.from_world(world, rng)
            ax = fig.add_subplot(1, count, k + 1)
            title = f"{world.name}\n{len(sim.radii)} obstacles, speed {sim.speed:g}"
            draw_simulator(ax, sim, rays=False, title=title)
            ax.plot(*sim.position, "o", color="#d62728", ms=5, zorder=8)
        fig.tight_layout()
        out = directory / f"family_{family}.png"
        fig.savefig(out)
        written.append(out)
    return written


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=200, help="tasks per family")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--families", nargs="*", default=list(FAMILIES))
    parser.add_argument("--pictures", type=Path, help="write family_<name>.png here")
    parser.add_argument("--into", type=Path, help="write the table into this page's block")
    args = parser.parse_args()
    if args.n > 0:
        text = table([family_stats(f, n=args.n, seed=args.seed) for f in args.families])
        print(text)
        if args.into is not None:
            import re

            page = args.into.read_text()
            mark = re.compile(r"(<!-- table[^>]*-->\n).*?(<!-- /table -->)", re.S)
            if not mark.search(page):
                raise SystemExit(f"{args.into}: no <!-- table --> block")
            args.into.write_text(mark.sub(lambda m: m.group(1) + "\n" + text.rstrip("\n")
                                          + "\n\n" + m.group(2), page))  # fmt: skip
    if args.pictures is not None:
        for path in pictures(args.pictures, args.seed):
            print(path)


if __name__ == "__main__":
    main()
