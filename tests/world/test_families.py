from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import shapely

from copi.errors import InvalidArgumentError
from copi.world import (
    CROWD_OBSTACLES,
    FAMILIES,
    MOVINGAI_ENV,
    PACKAGED_MAPS,
    Simulator,
    World,
    family_inputs,
    in_sight,
    is_star_shaped,
    maps_identity,
    movingai_dir,
    sample_start_goal,
    sample_world,
)


def _families() -> list:
    return list(FAMILIES)


def _world(family: str, k: int, seed: int = 0) -> tuple[World, np.random.Generator]:
    rng = np.random.default_rng([seed, k])
    return sample_world(family, rng), rng


def test_families_are_named_and_sorted() -> None:
    assert FAMILIES == ("circle-crossing", "crowd", "indoor", "maps", "polygon",
                        "square-crossing", "star")
    assert list(FAMILIES) == sorted(FAMILIES)


@pytest.mark.parametrize("family", _families())
def test_every_world_is_valid_and_gives_a_task(family: str) -> None:
    for k in range(30):
        world, rng = _world(family, k)
        assert world.polygon.is_valid, (k, shapely.is_valid_reason(world.polygon))
        assert world.name.startswith(f"{family}-")
        sim = Simulator.from_world(world, rng)
        assert np.hypot(*(sim.goal - sim.position)) >= 10.0
        assert len(sim.radii) >= 1
        assert (world.clearance(sim.centers) >= sim.radii - 1e-9).all()


@pytest.mark.parametrize("family", _families())
def test_same_seed_same_world_other_seed_other_world(family: str) -> None:
    worlds = [_world(family, k)[0] for k in range(8)]
    assert [_world(family, k)[0] for k in range(8)] == worlds
    assert sample_world(family, 5) == sample_world(family, 5)
    for a in range(len(worlds)):
        for b in range(a):
            assert worlds[a] != worlds[b], (a, b)


def test_star_is_the_paper_generator() -> None:
    from copi.world import random_world

    w = sample_world("star", 11)
    assert np.array_equal(w.boundary, random_world(11).boundary) and w.holes == ()


def _sees_every_vertex(ring: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Shapely's answer, independent of the kernel computation: which points see every
    vertex of the polygon (each sight line inside it, up to a hair's tolerance)."""
    poly = shapely.Polygon(ring).buffer(1e-7)
    lines = shapely.linestrings(np.stack([np.broadcast_to(points[:, None, :],
                                                          (len(points), len(ring), 2)),
                                          np.broadcast_to(ring[None], (len(points), len(ring),
                                                                       2))], axis=2))  # fmt: skip
    return shapely.within(lines, poly).all(axis=1)


def test_polygon_worlds_are_not_star_shaped_and_have_few_holes() -> None:
    holes = []
    rng = np.random.default_rng(0)
    for k in range(60):
        w, _ = _world("polygon", k)
        assert not is_star_shaped(w.boundary), k
        holes.append(len(w.holes))
        if k < 6:  # no point of a fine sample sees the whole boundary
            lo, hi = w.boundary.min(axis=0), w.boundary.max(axis=0)
            pts = rng.uniform(lo, hi, (3000, 2))
            pts = pts[shapely.contains_xy(shapely.Polygon(w.boundary), pts[:, 0], pts[:, 1])]
            assert len(pts) > 300 and not _sees_every_vertex(w.boundary, pts).any(), k
    assert set(holes) <= {0, 1, 2, 3} and len(set(holes)) >= 3


def test_the_star_shape_check_agrees_with_sight_lines() -> None:
    """The kernel test against shapely's sight lines on the paper's star worlds (seen whole
    from some point) and on an L and a U drawn by hand."""
    from copi.world import random_world

    ell = np.array([[0, 0], [6, 0], [6, 2], [2, 2], [2, 6], [0, 6]], dtype=float)
    u = np.array([[0, 0], [6, 0], [6, 6], [4, 6], [4, 2], [2, 2], [2, 6], [0, 6]], dtype=float)
    grid = np.stack(np.meshgrid(np.linspace(0.05, 5.95, 60), np.linspace(0.05, 5.95, 60)),
                    -1).reshape(-1, 2)  # fmt: skip
    for ring in (ell, u):
        inside = grid[shapely.contains_xy(shapely.Polygon(ring), grid[:, 0], grid[:, 1])]
        assert is_star_shaped(ring) == bool(_sees_every_vertex(ring, inside).any())
    rng = np.random.default_rng(1)
    for k in range(5):  # some point of a fine sample sees every vertex of a star world
        ring = random_world(k).boundary
        pts = rng.uniform(ring.min(axis=0), ring.max(axis=0), (3000, 2))
        assert is_star_shaped(ring) and _sees_every_vertex(ring, pts).any(), k


def _sight_share(family: str, n: int) -> float:
    seen = []
    for k in range(n):
        world, rng = _world(family, k)
        s, g = sample_start_goal(world, rng)  # the start and goal Simulator.from_world draws
        seen.append(in_sight(world, s, g, radius=0.3))
    return float(np.mean(seen))


def test_polygon_goal_is_in_sight_at_most_forty_percent_of_tasks() -> None:
    assert 0.15 < _sight_share("polygon", 200) <= 0.40


def test_indoor_goal_is_rarely_in_sight() -> None:
    assert _sight_share("indoor", 100) < 0.2


def test_crowd_is_the_polygon_world_with_a_dense_fast_crowd() -> None:
    assert CROWD_OBSTACLES.count == (25, 40) and CROWD_OBSTACLES.speed == 0.8
    for k in range(10):
        crowd, rng = _world("crowd", k)
        poly, _ = _world("polygon", k)
        assert crowd.obstacles == CROWD_OBSTACLES
        assert np.array_equal(crowd.boundary, poly.boundary)
        sim = Simulator.from_world(crowd, rng)
        assert 25 <= len(sim.radii) <= 40 and sim.speed == 0.8


def test_unknown_family_is_refused() -> None:
    with pytest.raises(
        InvalidArgumentError,
        match=r"^family must be one of crowd, indoor, maps, polygon, star(, [a-z-]+)*; got 'castle'$",
    ):
        sample_world("castle", 0)


def test_maps_without_data_are_refused_clearly(tmp_path: Path) -> None:
    missing = tmp_path / "nowhere"
    with pytest.raises(InvalidArgumentError) as err:
        sample_world("maps", 0, data_dir=missing)
    assert str(err.value) == (
        f"{missing} (data_dir) is not a directory; the maps family needs a directory of "
        ".map files"
    )
    with pytest.raises(InvalidArgumentError, match=r"holds no Moving AI map \(\*\.map\)"):
        movingai_dir(tmp_path)  # a directory without maps


def test_the_shipped_maps_are_the_default_and_the_variable_overrides_them(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.delenv(MOVINGAI_ENV, raising=False)
    monkeypatch.chdir(tmp_path)  # wherever the user runs it from
    assert movingai_dir() == PACKAGED_MAPS
    assert len(list(PACKAGED_MAPS.rglob("*.map"))) == 10
    monkeypatch.setenv(MOVINGAI_ENV, str(tmp_path / "env"))
    with pytest.raises(InvalidArgumentError) as err:
        movingai_dir()
    assert str(err.value) == (
        f"{tmp_path / 'env'} (${MOVINGAI_ENV}) is not a directory; the maps family needs a "
        f"directory of .map files (unset ${MOVINGAI_ENV} to use the maps copi ships)"
    )


def test_the_shipped_maps_match_their_provenance() -> None:
    import csv
    import hashlib

    with open(PACKAGED_MAPS / "PROVENANCE.tsv", newline="") as fh:
        rows = {r["local_file"]: r["sha256"] for r in csv.DictReader(fh, delimiter="\t")}
    found = {p.relative_to(PACKAGED_MAPS).as_posix() for p in PACKAGED_MAPS.rglob("*.map")}
    assert found == set(rows)
    for rel, sha in rows.items():
        assert hashlib.sha256((PACKAGED_MAPS / rel).read_bytes()).hexdigest() == sha, rel
    assert "Open Data Commons Attribution" in (PACKAGED_MAPS / "README.md").read_text()


def test_the_map_set_identity_follows_the_content(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    import shutil

    copy = tmp_path / "copy"
    shutil.copytree(PACKAGED_MAPS, copy)
    assert maps_identity(copy) == maps_identity()  # where the maps lie does not matter
    (copy / "mapf" / "empty-32-32.map").unlink()
    fewer = maps_identity(copy)
    assert fewer != maps_identity()
    shutil.copy(PACKAGED_MAPS / "mapf" / "empty-32-32.map", copy / "mapf" / "other.map")
    assert maps_identity(copy) not in (fewer, maps_identity())  # a renamed map is another set
    monkeypatch.setenv(MOVINGAI_ENV, str(copy))
    assert family_inputs("maps") == {"maps_sha": maps_identity(copy)}
    assert family_inputs("indoor") == {}


def _write_map(path: Path, rows: list[str]) -> None:
    head = f"type octile\nheight {len(rows)}\nwidth {len(rows[0])}\nmap\n"
    path.write_text(head + "\n".join(rows) + "\n")


def test_maps_from_the_environment_with_diagonal_blocks(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    # pairs of blocks that touch only at a corner would make holes meeting at a point
    grid = np.full((40, 40), ".")
    for cx in range(4, 36, 8):
        for cy in range(4, 36, 8):
            grid[cy : cy + 2, cx : cx + 2] = "@"
            grid[cy + 2 : cy + 4, cx + 2 : cx + 4] = "@"
    rows = ["".join(r) for r in grid]
    (tmp_path / "maps").mkdir()
    _write_map(tmp_path / "maps" / "checker.map", rows)
    monkeypatch.setenv(MOVINGAI_ENV, str(tmp_path / "maps"))
    for k in range(10):
        world, rng = _world("maps", k)
        assert world.polygon.is_valid and world.name.startswith("maps-checker-")
        assert len(world.holes) >= 4
        Simulator.from_world(world, rng)


def test_map_obstacles_fit_their_passages() -> None:
    names = set()
    for k in range(40):
        world, _ = _world("maps", k)
        assert world.obstacles is not None
        lo, hi = world.obstacles.radius
        assert 0 < lo <= hi <= 1.0
        names.add(world.name.split("-x")[0])
    assert len(names) >= 5  # windows come from many maps


def test_a_ctrl_c_inside_a_sampler_s_compiled_call_is_not_the_sampler_s_error() -> None:
    """numba reports a Ctrl-C that lands in a compiled call as a SystemError raised while
    handling it: that is the user's stop, passed on, not a broken sampler."""
    from copi.world import register_family, unregister_family

    def pressed(rng: np.random.Generator, *, name: str | None = None) -> None:
        try:
            raise KeyboardInterrupt
        except KeyboardInterrupt:
            raise SystemError("returned a result with an exception set") from None

    def broken(rng: np.random.Generator, *, name: str | None = None) -> None:
        raise SystemError("its own")

    register_family("fz-pressed", pressed, summary="a sampler that meets a Ctrl-C")
    register_family("fz-own", broken, summary="a sampler with a SystemError of its own")
    try:
        with pytest.raises(SystemError, match="exception set"):
            sample_world("fz-pressed", 0)
        with pytest.raises(InvalidArgumentError, match="raised SystemError: its own"):
            sample_world("fz-own", 0)
    finally:
        unregister_family("fz-pressed")
        unregister_family("fz-own")
