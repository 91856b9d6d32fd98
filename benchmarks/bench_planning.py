"""Speed of the reference planners.

Goals (issue: exact optimal reference paths):
- build + query of a 12-gon snapshot with 15 frozen discs <= 30 ms, reported as a ratio
  against extremitypathfinder on the same polygon (optional dependency: skipped with a
  note when it is not installed), with the same length;
- grid A* time per query on the 512 x 512 Moving AI maps.
"""

from __future__ import annotations

import math
import time
from pathlib import Path

import numpy as np
import shapely

from benchmarks._timing import Timing, fmt, note, report, show
from copi.planning import VisibilityGraph, configuration_space, shortest_path
from copi.planning._grid import GridPlanner
from copi.planning.movingai import read_map, read_scenarios
from copi.world import PACKAGED_MAPS, ObstacleSpec, Simulator, WorldParams, random_world

DATA = Path(__file__).resolve().parents[1] / "tests" / "data"
"""The tests' reference data (Moving AI scenarios; their maps are the ones copi ships)."""


def snapshots(n: int) -> list[tuple]:
    """n paper-style snapshots: a 12-gon, a start and goal, 15 frozen discs."""
    out = []
    k = 0
    while len(out) < n:
        rng = np.random.default_rng([7, k])
        k += 1
        world = random_world(rng, params=WorldParams(sides=(12, 12)))
        sim = Simulator.from_world(world, rng, obstacles=ObstacleSpec(count=(15, 15)))
        try:
            plan = shortest_path(
                world, sim.position, sim.goal, radius=0.3, centers=sim.centers, radii=sim.radii
            )
        except Exception:
            continue  # goal under a frozen disc
        if plan.found:
            out.append((world, sim.position, sim.goal, sim.centers, sim.radii))
    return out


def _component(geom: shapely.Geometry, p: np.ndarray) -> shapely.Polygon:
    parts = shapely.get_parts(geom)
    return next(g for g in parts if shapely.intersects_xy(g, p[0], p[1]))


def bench_snapshots() -> bool:
    try:
        from extremitypathfinder import PolygonEnvironment
    except ImportError:  # pragma: no cover - optional
        PolygonEnvironment = None
    snaps = snapshots(20)
    ours_full, ours_same, epf, ratios = [], [], [], []
    for i, (world, s, g, c, r) in enumerate(snaps):
        t0 = time.perf_counter()
        plan = shortest_path(world, s, g, radius=0.3, centers=c, radii=r)
        ours_full.append(time.perf_counter() - t0)
        # The same problem as extremitypathfinder is given it: a point agent, discs as
        # 16-gons (quad_segs 4), the connected polygon holding the start.
        poly = _component(configuration_space(world, centers=c, radii=r + 0.3, quad_segs=4), s)
        poly = shapely.geometry.polygon.orient(poly, 1.0)
        t0 = time.perf_counter()
        mine = VisibilityGraph.from_geometry(poly).shortest_path(s, g)
        ours_same.append(time.perf_counter() - t0)
        if PolygonEnvironment is not None and i < 5:
            t0 = time.perf_counter()
            env = PolygonEnvironment()
            env.store(
                [tuple(x) for x in np.asarray(poly.exterior.coords)[:-1]],
                [[tuple(x) for x in np.asarray(h.coords)[:-1]] for h in poly.interiors],
            )
            if not env.prepared:
                env.prepare()
            _, length = env.find_shortest_path(tuple(s), tuple(g))
            epf.append(time.perf_counter() - t0)
            ratios.append(epf[-1] / ours_same[-1])
            assert length is not None and math.isclose(length, mine.length, abs_tol=1e-6), (
                length,
                mine.length,
            )
        del plan
    rows = [
        Timing("copi shortest_path (radius 0.3, circles as 64-gons)", float(np.median(ours_full))),
        Timing("copi visibility graph, same polygon as epf", float(np.median(ours_same))),
    ]
    if epf:
        rows.append(Timing("extremitypathfinder prepare + query", float(np.median(epf))))
    ok = report(
        "build + query, 12-gon + 15 frozen discs (median over snapshots)",
        rows,
        "extremitypathfinder prepare + query" if epf else None,
        {"copi shortest_path (radius 0.3, circles as 64-gons)": 30e-3},
    )
    if ratios:
        note(
            f"extremitypathfinder / copi on the same polygon: median {np.median(ratios):.0f}x "
            f"over {len(ratios)} snapshots, equal lengths (1e-6)"
        )
    else:
        note("extremitypathfinder not installed: no ratio (pip install extremitypathfinder)")
    return ok


def bench_grid() -> None:
    cells = []
    for rel, n in (("bg512/AR0011SR.map.scen", 400), ("maze/maze512-32-9.map.scen", 150)):
        scen = DATA / "movingai" / rel
        if not scen.exists():
            continue
        lines = read_scenarios(scen)
        lines = [lines[i] for i in np.linspace(0, len(lines) - 1, n).astype(int)]
        planner = GridPlanner(read_map(PACKAGED_MAPS / rel.split(".scen")[0]).free)
        times = []
        for s in lines:
            t0 = time.perf_counter()
            planner.shortest_path(s.start, s.goal)
            times.append(time.perf_counter() - t0)
        cells.append([rel, str(n), fmt(float(np.median(times))), fmt(float(np.mean(times)))])
    show("grid A*", ["map", "queries", "median per query", "mean per query"], cells)


def main() -> bool:
    ok = bench_snapshots()
    bench_grid()
    return ok


if __name__ == "__main__":
    raise SystemExit(0 if main() else 1)
