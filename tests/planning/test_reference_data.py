"""Planners against data nobody here wrote (tests/data, provenance in its README)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import shapely
from shapely.geometry import Polygon, box

from copi.errors import InvalidQueryError
from copi.planning import VisibilityGraph, shortest_path
from copi.planning._grid import GridPlanner
from copi.planning.movingai import (
    cell_center,
    free_geometry,
    map_world,
    read_map,
    read_scenarios,
)
from tests.common import DATA, MAPS

EPF = DATA / "polygons" / "extremitypathfinder" / "cases.json"
MOVINGAI = DATA / "movingai"
SCENARIOS = sorted(MOVINGAI.rglob("*.scen"))


def _epf_environments() -> dict:
    return json.loads(EPF.read_text())["environments"]


def _epf_geometry(env: dict):
    if env["type"] == "grid":
        cells = [box(x, y, x + 1, y + 1) for x, y in env["blocked_cells"]]
        return box(0, 0, env["size_x"], env["size_y"]).difference(shapely.union_all(cells))
    holes = shapely.union_all([Polygon(h) for h in env["holes"]])
    return Polygon(env["boundary"]).difference(holes)


@pytest.mark.parametrize("name", sorted(_epf_environments()))
def test_extremitypathfinder_cases_both_directions(name: str) -> None:
    env = _epf_environments()[name]
    graph = VisibilityGraph.from_geometry(_epf_geometry(env))
    for q in env["queries"]:
        for s, g in ((q["start"], q["goal"]), (q["goal"], q["start"])):
            plan = graph.shortest_path(s, g)
            if q["expected_length"] is None:
                assert not plan.found, (s, g)
                continue
            assert plan.found, (s, g)
            assert plan.length == pytest.approx(q["expected_length"], abs=1e-6), (s, g)
            # the path's own segments add up to the length, from start to goal
            assert np.hypot(*np.diff(plan.path, axis=0).T).sum() == pytest.approx(plan.length)
            assert plan.path[0].tolist() == list(map(float, s))
    for s, g in env.get("invalid_queries_must_raise", []):
        with pytest.raises(InvalidQueryError, match="must lie in the free space"):
            graph.shortest_path(s, g)


def _tolerance(scen: Path) -> float:
    rel = scen.relative_to(MOVINGAI).as_posix()
    if rel.startswith("bg512/legacy/"):
        return 1e-2
    if "legacy/" in rel or rel == "dao/arena2.map.scen":
        return 1e-3
    return 1e-6


def _map_for(scen: Path, name: str) -> Path:
    """The scenario's map, among the maps copi ships (same folders as the scenarios)."""
    base = Path(name).name
    rel = scen.parent.relative_to(MOVINGAI)
    for folder in (MAPS / rel, MAPS / rel.parent):
        if (folder / base).exists():
            return folder / base
    raise FileNotFoundError(f"no map {base} for {scen}")


def _check_grid(scen: Path, sample: int | None) -> int:
    lines = read_scenarios(scen)
    grid = read_map(_map_for(scen, lines[0].map_name))
    planner = GridPlanner(grid.free)
    tol = _tolerance(scen)
    if sample is not None and len(lines) > sample:
        lines = [lines[i] for i in np.linspace(0, len(lines) - 1, sample).astype(int)]
    for s in lines:
        assert (s.width, s.height) == (grid.width, grid.height)
        plan = planner.shortest_path(s.start, s.goal)
        assert abs(plan.length - s.optimal_length) <= tol * max(1.0, s.optimal_length), (
            f"{scen.name}:{s.line}: expected {s.optimal_length}, got {plan.length}"
        )
        if plan.path is not None and len(plan.path) > 1:
            steps = np.abs(np.diff(plan.path, axis=0))
            assert steps.max() <= 1 and grid.free[plan.path[:, 1], plan.path[:, 0]].all()
    return len(lines)


@pytest.mark.parametrize("scen", SCENARIOS, ids=lambda p: p.relative_to(MOVINGAI).as_posix())
def test_grid_astar_matches_movingai_sample(scen: Path) -> None:
    # every line of the small files; 150 evenly spread lines (longest included) of large ones
    assert _check_grid(scen, sample=150) > 0


@pytest.mark.slow
@pytest.mark.parametrize("scen", SCENARIOS, ids=lambda p: p.relative_to(MOVINGAI).as_posix())
def test_grid_astar_matches_every_movingai_line(scen: Path) -> None:
    assert _check_grid(scen, sample=None) == len(read_scenarios(scen))


SMALL_MAPS = sorted(
    [p for p in SCENARIOS if p.parent.name in ("mapf", "dao") and "arena2" not in p.name],
    key=str,
)


@pytest.mark.parametrize("scen", SMALL_MAPS, ids=lambda p: p.relative_to(MOVINGAI).as_posix())
def test_continuous_is_between_straight_line_and_octile(scen: Path) -> None:
    lines = read_scenarios(scen)
    grid = read_map(_map_for(scen, lines[0].map_name))
    graph = VisibilityGraph.from_geometry(free_geometry(grid))
    picks = [lines[i] for i in np.linspace(0, len(lines) - 1, 40).astype(int)]
    for s in picks:
        a, b = cell_center(grid, s.start), cell_center(grid, s.goal)
        plan = graph.shortest_path(a, b)
        assert plan.found
        assert plan.length <= s.optimal_length + 1e-6 * max(1, s.optimal_length)
        assert plan.length >= np.hypot(*(a - b)) - 1e-9


def test_a_map_becomes_a_world() -> None:
    grid = read_map(MAPS / "mapf" / "room-32-32-4.map")
    world = map_world(grid)
    assert world.polygon.area == pytest.approx(grid.free.sum(), rel=0.02)
    lines = read_scenarios(MOVINGAI / "mapf" / "room-32-32-4-random-1.scen")
    s = lines[-1]
    plan = shortest_path(world, cell_center(grid, s.start), cell_center(grid, s.goal))
    assert plan.length <= s.optimal_length + 1e-6


MESH = DATA / "polygons" / "ironharvest_mesh" / "scene_mp_2p_01.mesh"


def _check_mesh(sample: int | None) -> int:
    from copi.planning.mesh import read_mesh

    graph = VisibilityGraph.from_geometry(read_mesh(MESH), through_pinch_points=False)
    rows = [ln.split() for ln in MESH.with_suffix(".mesh.scen").read_text().splitlines()[1:]]
    rows = [r for r in rows if r]
    if sample is not None:
        rows = [rows[i] for i in np.linspace(0, len(rows) - 1, sample).astype(int)]
    for r in rows:
        s, g, expected = (float(r[4]), float(r[5])), (float(r[6]), float(r[7])), float(r[8])
        plan = graph.shortest_path(s, g)
        assert plan.length == pytest.approx(expected, rel=1e-9, abs=1e-9), r
    return len(rows)


def test_iron_harvest_mesh_sample() -> None:
    assert _check_mesh(sample=100) == 100


@pytest.mark.slow
def test_iron_harvest_mesh_every_query() -> None:
    assert _check_mesh(sample=None) == 2000


def test_pinch_points_are_passable_only_in_the_closed_convention() -> None:
    # two squares touching at one corner: a path through the corner exists only when
    # pinch points are part of the free space
    two = shapely.union_all([box(0, 0, 1, 1), box(1, 1, 2, 2)])
    closed = VisibilityGraph.from_geometry(two).shortest_path([0.5, 0.5], [1.5, 1.5])
    assert closed.length == pytest.approx(2**0.5)
    opened = VisibilityGraph.from_geometry(two, through_pinch_points=False)
    assert not opened.shortest_path([0.5, 0.5], [1.5, 1.5]).found


def test_bad_mesh_files_are_refused(tmp_path: Path) -> None:
    from copi.errors import MapFileError
    from copi.planning.mesh import read_mesh

    (tmp_path / "a.mesh").write_text("mesh\n2\n")
    with pytest.raises(MapFileError, match="expected 'mesh' and version '3' first"):
        read_mesh(tmp_path / "a.mesh")
    (tmp_path / "b.mesh").write_text("mesh\n3\n3 1\n0 0\n1 0\n")
    with pytest.raises(MapFileError, match="malformed mesh"):
        read_mesh(tmp_path / "b.mesh")
    with pytest.raises(MapFileError, match="cannot read"):
        read_mesh(tmp_path / "missing.mesh")
