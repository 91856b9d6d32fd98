from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from copi.errors import WorldFileError
from copi.world import ObstacleSpec, load_worlds, random_world, sample_start_goal, save_worlds
from tests.common import NAMED, U_TRAP


@settings(
    max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(
    seeds=st.lists(st.integers(0, 2**32 - 1), min_size=1, max_size=4),
    with_task=st.booleans(),
    spec=st.none()
    | st.builds(
        ObstacleSpec, count=st.tuples(st.just(3), st.integers(3, 9)), radius=st.just((0.5, 0.9))
    ),
)
def test_round_trip(tmp_path: Path, seeds: list[int], with_task: bool, spec) -> None:
    worlds = []
    for s in seeds:
        w = random_world(s).replace(obstacles=spec)
        if with_task:
            start, goal = sample_start_goal(w, s)
            w = w.replace(start=start, goal=goal)
        worlds.append(w)
    worlds += list(NAMED.values())
    save_worlds(worlds, tmp_path / "w.json")
    assert load_worlds(tmp_path / "w.json") == worlds
    text = (tmp_path / "w.json").read_text()
    assert json.loads(text) == [w.to_dict() for w in worlds]
    # compact: points stay whole on a line, lines stay short, no line is a lone number
    lines = text.splitlines()
    assert all(len(ln) <= 120 for ln in lines)
    assert not any(ln.strip().rstrip(",").replace(".", "").lstrip("-").isdigit() for ln in lines)
    assert len(lines) < 20 * len(worlds) + sum(len(w.boundary) for w in worlds) // 3
    text = (tmp_path / "w.json").read_text()
    assert json.loads(text) == [w.to_dict() for w in worlds]
    # compact: points stay whole on a line, lines stay short, no line is a lone number
    lines = text.splitlines()
    assert all(len(ln) <= 120 for ln in lines)
    assert not any(ln.strip().rstrip(",").replace(".", "").lstrip("-").isdigit() for ln in lines)
    assert len(lines) < 20 * len(worlds) + sum(len(w.boundary) for w in worlds) // 3


def test_the_design_example_loads(tmp_path: Path) -> None:
    text = """{"name": "u-trap",
 "boundary": [[0, 0], [40, 0], [40, 30], [0, 30]],
 "holes": [[[10, 5], [30, 5], [30, 25], [28, 25], [28, 7], [12, 7], [12, 25], [10, 25]]],
 "start": [20, 15], "goal": [20, 28],
 "obstacles": {"count": 12, "radius": 0.75, "speed": 0.6}}"""
    (tmp_path / "u.json").write_text(text)
    (w,) = load_worlds(tmp_path / "u.json")
    assert w == U_TRAP.replace(obstacles=ObstacleSpec(count=(12, 12), radius=(0.75, 0.75)))


def _write(tmp_path: Path, text: str) -> Path:
    p = tmp_path / "bad.json"
    p.write_text(text)
    return p


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ('[{"boundary": [[0,0],[1,0]', ":1:27: not valid JSON (Expecting ',' delimiter)"),
        ("", ":1:1: not valid JSON (Expecting value)"),
        ("[]", ":1:1: expected a world object or a non-empty list"),
        ('"hello"', ":1:1: a world must be a JSON object; got a string"),
        (
            '[\n {"boundary": [[0,0],[4,0],[4,4],[0,4]]},\n {"name": "x",\n  "boundary": [[0,0],[4,4],[4,0],[0,4]]}\n]',
            ":4:15: world 'x': boundary must be a simple polygon; edges 0 and 2 cross at (2, 2)",
        ),
        (
            '{"boundary": [[0,0],[9,0],[9,9],[0,9]],\n "holes": [\n  [[1,1],[2,1],[2,2]],\n  [[5,5],[12,5],[12,6]]]}',
            ":4:3: world 'world': hole 1 must lie strictly inside the boundary; its vertex 1 (12, 5) does not",
        ),
        (
            '{"boundary": [[0,0],[9,0],[9,9]], "colour": 3}',
            ":1:45: world 'world': unknown keys ['colour']",
        ),
        (
            '{"boundary": "square"}',
            ":1:14: world 'world': boundary must be a list of numbers; got a string",
        ),
        (
            '{"boundary": [[0,0],[9,0],[9,9]],\n "obstacles": {"count": -1}}',
            ":2:15: world 'world': obstacles.count must be finite with 0 <= low <= high",
        ),
        ('{"holes": []}', ":1:1: world 'world': missing key 'boundary'"),
    ],
)
def test_bad_files_are_refused_with_a_line(tmp_path: Path, text: str, expected: str) -> None:
    p = _write(tmp_path, text)
    with pytest.raises(WorldFileError) as err:
        load_worlds(p)
    assert str(err.value).startswith(f"{p}{expected}"), str(err.value)


def test_unreadable_files(tmp_path: Path) -> None:
    with pytest.raises(WorldFileError, match="no such world file"):
        load_worlds(tmp_path / "missing.json")
    with pytest.raises(WorldFileError, match="is a directory"):
        load_worlds(tmp_path)
    (tmp_path / "bin.json").write_bytes(b"\x89PNG\r\n\x1a\n\xff\xfe")
    with pytest.raises(WorldFileError, match="not a text file"):
        load_worlds(tmp_path / "bin.json")


def test_failed_save_leaves_the_old_file(tmp_path: Path) -> None:
    p = tmp_path / "w.json"
    save_worlds(U_TRAP, p)
    before = p.read_bytes()
    with pytest.raises(WorldFileError, match="save_worlds takes World objects"):
        save_worlds([U_TRAP, "not a world"], p)  # type: ignore[list-item]
    assert p.read_bytes() == before
    assert sorted(x.name for x in tmp_path.iterdir()) == ["w.json"]
    assert json.loads(before)[0]["name"] == "u-trap"
    assert np.allclose(load_worlds(p)[0].boundary, U_TRAP.boundary)


# -- hostile and malformed files (issue 14) ------------------------------------------------

_json = st.recursive(
    st.none() | st.booleans() | st.floats(allow_nan=False) | st.integers() | st.text(max_size=5),
    lambda children: st.lists(children, max_size=4)
    | st.dictionaries(
        st.sampled_from(["name", "boundary", "holes", "start", "goal", "obstacles", "count",
                         "radius", "speed", "x"]),
        children, max_size=5,
    ),  # fmt: skip
    max_leaves=20,
)
_coord = st.one_of(
    st.floats(-50, 50),
    st.integers(-50, 50),
    st.just(10**400),
    st.just(float("nan")),
    st.just("1"),
    st.just(None),
)
_ring = st.lists(st.lists(_coord, min_size=2, max_size=2), min_size=0, max_size=6)


def _world_like() -> st.SearchStrategy[dict]:
    return st.fixed_dictionaries(
        {"boundary": _ring},
        optional={
            "name": st.text(max_size=4) | st.integers(),
            "holes": st.lists(_ring, max_size=2),
            "start": st.lists(_coord, max_size=3),
            "goal": st.lists(_coord, max_size=3),
            "obstacles": st.fixed_dictionaries(
                {}, optional={"count": _coord, "radius": _coord, "speed": _coord}
            ),
        },
    )


def _check_loads_or_refuses(path, text: str) -> None:
    path.write_text(text, encoding="utf-8")
    try:
        worlds = load_worlds(path)
    except WorldFileError as exc:
        assert str(exc).startswith(str(path)) and "\n" not in str(exc)
        return
    assert worlds and all(w.polygon.is_valid for w in worlds)


@settings(max_examples=150, deadline=None)
@given(value=_json)
def test_any_json_loads_or_is_refused_in_one_line(tmp_path_factory, value) -> None:
    _check_loads_or_refuses(tmp_path_factory.mktemp("j") / "w.json", json.dumps(value))


@settings(max_examples=200, deadline=None)
@given(worlds=st.lists(_world_like(), min_size=1, max_size=3) | _world_like())
def test_world_like_files_load_or_are_refused_in_one_line(tmp_path_factory, worlds) -> None:
    text = json.dumps(worlds, default=str)
    _check_loads_or_refuses(tmp_path_factory.mktemp("w") / "w.json", text)


@settings(max_examples=60, deadline=None)
@given(blob=st.binary(max_size=200))
def test_random_bytes_are_refused_in_one_line(tmp_path_factory, blob: bytes) -> None:
    path = tmp_path_factory.mktemp("b") / "w.json"
    path.write_bytes(blob)
    try:
        worlds = load_worlds(path)
    except WorldFileError as exc:
        assert str(exc).startswith(str(path)) and "\n" not in str(exc)
        return
    # bytes that happen to be a world file: what loaded is a valid world, and it is what
    # the file says (saved and read back, the same worlds)
    assert worlds and all(w.polygon.is_valid and w.polygon.area > 0 for w in worlds)
    again = path.with_name("again.json")
    save_worlds(worlds, again)
    assert [w.to_dict() for w in load_worlds(again)] == [w.to_dict() for w in worlds]


def test_deep_nesting_huge_numbers_and_a_byte_order_mark(tmp_path) -> None:
    deep = tmp_path / "deep.json"
    deep.write_text("[" * 100_000 + "]" * 100_000)
    with pytest.raises(WorldFileError, match="nested too deeply"):
        load_worlds(deep)
    big = tmp_path / "big.json"
    big.write_text('{"boundary": [[0, 0], [1' + "0" * 400 + ', 0], [4, 4]]}')
    with pytest.raises(WorldFileError, match="too large for a float"):
        load_worlds(big)
    bom = tmp_path / "bom.json"
    bom.write_bytes(b"\xef\xbb\xbf" + b'{"name": "b", "boundary": [[0, 0], [20, 0], [20, 20]]}')
    assert [w.name for w in load_worlds(bom)] == ["b"]


def test_a_hole_sharing_an_edge_with_the_boundary_is_named(tmp_path) -> None:
    path = tmp_path / "edge.json"
    path.write_text(
        '{"name": "c", "boundary": [[0, 0], [20, 0], [20, 20], [0, 20]],'
        ' "holes": [[[0, 5], [5, 5], [5, 10], [0, 10]]]}'
    )
    with pytest.raises(WorldFileError, match="hole 0 shares an edge with the boundary"):
        load_worlds(path)


def test_world_files_are_bounded(tmp_path) -> None:
    path = tmp_path / "many.json"
    one = {"boundary": [[0, 0], [20, 0], [20, 20]]}
    path.write_text(json.dumps([one] * 30))
    with pytest.raises(WorldFileError, match="30 worlds, more than a world file may hold"):
        load_worlds(path, max_worlds=20)
    with pytest.raises(WorldFileError, match="bytes, more than a world file may hold"):
        load_worlds(path, max_bytes=100)
    assert len(load_worlds(path)) == 30
