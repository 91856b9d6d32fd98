"""The causal map (paper §III): update and inference against hand-built worlds whose
values are worked out by hand, the static map's verdict on options against a hand-drawn
grid, persistence, and the strategy on the U-trap and over a life."""

from __future__ import annotations

import math
import zipfile
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from copi.errors import InvalidArgumentError
from copi.methods import make_agent
from copi.online import CausalMap, CausalMapFormatError, CausalStrategy, Steering
from copi.online._causal_kernels import OFFSETS, plausible_options
from copi.runs import run_episode
from copi.world import Simulator
from tests.baselines._support import TRAP_GOAL, route_length
from tests.common import U_TRAP

E, NE, N, NW, W, SW, S, SE = range(8)


def _small(**kw: float) -> CausalMap:
    # 4 x 4 places of side 1 (extent 2); place (i, j) is j * 4 + i.
    return CausalMap(extent=2.0, place=1.0, prior=1.0, patience=10, **kw)


def _hand_built(cmap: CausalMap) -> tuple[int, int, int]:
    """p = (0, 0), its east neighbour g = (1, 0) is the goal, r = (0, 1) north of p.

    E from p: tried 4 times, 3 reached g (2 steps each), 1 ended in a contact (1 step).
    N from p: 2 tries, both reached r in 1 step. SE from r: 2 tries, both reached g in 1.
    With no way allowed by the static map (the prior is "stay put for 10 steps"):
      V(r) = (10 + V(r) + 2 + 0) / 3                    -> V(r) = 6
      Q(p, N) = (10 + V(p) + 2 + 2 V(r)) / 3 = (24 + V(p)) / 3
      Q(p, E) = (10 + V(p) + 7 + C + 3 * 0) / 5 = (17 + C + V(p)) / 5
    so with C = 50: V(p) = 12 by N (Q(p, E) = 15.8 there); with C = 0: V(p) = 4.25 by E.
    """
    p, g, r = 0, 1, 4
    for _ in range(3):
        cmap.record(p, 0, E, g, 2, False)
    cmap.record(p, 0, E, None, 1, True)
    for _ in range(2):
        cmap.record(p, 0, N, r, 1, False)
        cmap.record(r, 0, SE, g, 1, False)
    return p, g, r


def _solve(cmap: CausalMap, goal: int) -> tuple[np.ndarray, np.ndarray]:
    plaus = np.zeros((cmap.m * cmap.m, 8), dtype=bool)
    return cmap.solve(goal, plaus, np.arange(cmap.m * cmap.m), tol=1e-12, max_sweeps=100_000)


def test_values_and_best_options_of_a_hand_built_world() -> None:
    cmap = _small(contact_cost=50.0)
    p, g, r = _hand_built(cmap)
    value, best = _solve(cmap, g)
    assert value[g] == 0.0 and best[g] == -1
    assert value[r] == pytest.approx(6.0, abs=1e-6) and best[r] == SE
    assert value[p] == pytest.approx(12.0, abs=1e-6) and best[p] == N
    assert cmap.option_value(p, E, value, False) == pytest.approx(15.8, abs=1e-6)
    # Places never visited have no way to the goal (the static map allowed nothing).
    assert value[15] >= 1e9 and best[15] == -1
    # Contacts cost nothing: the short, risky option wins.
    free = _small(contact_cost=0.0)
    _hand_built(free)
    value, best = _solve(free, g)
    assert value[p] == pytest.approx(4.25, abs=1e-6) and best[p] == E


def test_the_static_map_is_the_prior_of_untried_options() -> None:
    # Everything allowed and nothing tried: values are octile distances in places.
    cmap = _small()
    plaus = np.ones((16, 8), dtype=bool)
    for p in range(16):  # the map's edge: no neighbour there
        for a in range(8):
            plaus[p, a] = cmap.neighbour(p, a) >= 0
    value, _ = cmap.solve(15, plaus, np.arange(16), tol=1e-12)
    for p in range(16):
        j, i = divmod(p, 4)
        dx, dy = 3 - i, 3 - j
        octile = max(dx, dy) + (math.sqrt(2) - 1) * min(dx, dy)
        assert value[p] == pytest.approx(octile, abs=1e-9)
    # Experience overrides it: an option that always went nowhere is avoided.
    for _ in range(20):
        cmap.record(10, 0, NE, 10, 10, False)
    value, best = cmap.solve(15, plaus, np.arange(16), tol=1e-12)
    assert best[10] != NE
    assert value[10] == pytest.approx(2.0, abs=1e-9)  # E then N, or N then E


def test_contexts_decide_at_the_state_the_agent_is_in() -> None:
    cmap = _small(contact_cost=50.0, context_prior=2.0)
    p, g = 0, 1
    for _ in range(4):
        cmap.record(p, 7, E, None, 1, True)  # in context 7, E meets an obstacle
        cmap.record(p, 3, E, g, 1, False)  # in context 3 it gets through
    value = np.zeros(16)
    # Pooled: (1 prior stay 10 + 8 steps + 4 * 50 + 0) / 9
    pooled = (10 + 8 + 200) / 9
    assert cmap.option_value(p, E, value, False) == pytest.approx(pooled)
    assert cmap.option_value(p, E, value, False, 7) == pytest.approx((2 * pooled + 4 + 200) / 6)
    assert cmap.option_value(p, E, value, False, 3) == pytest.approx((2 * pooled + 4) / 6)
    # A context never seen there falls back on the pooled outcomes.
    assert cmap.option_value(p, E, value, False, 11) == pytest.approx(pooled)


def test_options_the_occupancy_grid_allows() -> None:
    k, m = 2, 3  # 3 x 3 places of 2 x 2 cells
    free = np.ones((6, 6), dtype=bool)
    free[:, 2] = False  # a wall between place column 0 and 1 ...
    free[4, 2] = True  # ... with a gap in place row 2
    out = np.zeros((9, 8), dtype=bool)
    seen = np.zeros(36, dtype=np.int64)
    queue = np.empty(4 * k * k, dtype=np.int64)
    plausible_options(free, k, m, 0, m, 0, m, OFFSETS, out, seen, queue)
    assert not out[0, E] and not out[3, E]  # rows 0, 1: the wall
    assert out[6, E]  # row 2: through the gap
    assert out[1, E] and out[1, N] and not out[4, W]
    assert not out[0, W] and not out[0, S]  # off the map
    assert (seen == 0).all()  # the work array is left ready for the next call
    # Corners are not cut: a diagonal between two blocked orthogonal cells is refused.
    grid = np.zeros((4, 4), dtype=bool)
    grid[0:2, 0:2] = grid[2:4, 2:4] = True  # places 0 and 3 free, 1 and 2 walls
    out = np.zeros((4, 8), dtype=bool)
    work = (np.zeros(16, dtype=np.int64), np.empty(16, dtype=np.int64))
    plausible_options(grid, 2, 2, 0, 2, 0, 2, OFFSETS, out, *work)
    assert not out[0, NE] and not out[3, SW]
    grid[1, 2] = True  # one orthogonal cell free: round the corner
    plausible_options(grid, 2, 2, 0, 2, 0, 2, OFFSETS, out, *work)
    assert out[0, NE] and out[3, SW]


_records = st.lists(
    st.tuples(
        st.integers(0, 15), st.integers(-1, 5), st.integers(0, 7), st.integers(0, 15),
        st.integers(1, 30), st.booleans(),
    ),
    max_size=40,
)  # fmt: skip


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(records=_records)
def test_save_and_load_round_trip(tmp_path: Path, records: list) -> None:
    cmap = _small()
    for p, c, a, q, steps, contact in records:
        cmap.record(p, c, a, None if contact else q, steps, contact)
    occ = np.linspace(-2, 4, 100).reshape(10, 10)
    path = tmp_path / "life.npz"
    cmap.save(path, world="w-1", capabilities="abc", occupancy=occ)
    back, occ_back = CausalMap.load(path, world="w-1", capabilities="abc")
    assert back.params == cmap.params
    assert np.array_equal(back.n, cmap.n) and np.array_equal(back.steps, cmap.steps)
    assert np.array_equal(back.contacts, cmap.contacts)
    assert back.outcomes == cmap.outcomes
    assert back.by_context == cmap.by_context
    assert occ_back is not None and np.array_equal(occ_back, occ)
    plaus = np.ones((16, 8), dtype=bool)
    for goal in (0, 9):
        v1, b1 = cmap.solve(goal, plaus, np.arange(16))
        v2, b2 = back.solve(goal, plaus, np.arange(16))
        assert np.array_equal(v1, v2) and np.array_equal(b1, b2)


def test_bad_files_are_refused_saying_what_differs(tmp_path: Path) -> None:
    cmap = _small()
    _hand_built(cmap)
    path = cmap.save(tmp_path / "life.npz", world="indoor-life-0003-seed-0", capabilities="c1")
    with pytest.raises(CausalMapFormatError, match="a causal map of world 'indoor-life-0003-seed-0', not of 'indoor-life-0004-seed-0'"):
        CausalMap.load(path, world="indoor-life-0004-seed-0")
    with pytest.raises(CausalMapFormatError, match="learnt with other capabilities"):
        CausalMap.load(path, capabilities="c2")
    cut = tmp_path / "cut.npz"
    cut.write_bytes(path.read_bytes()[:300])
    with pytest.raises(CausalMapFormatError, match="cut.npz: not a complete .npz archive"):
        CausalMap.load(cut)
    foreign = tmp_path / "foreign.npz"
    np.savez(foreign, x=np.zeros(3))
    with pytest.raises(CausalMapFormatError, match="not a copi causal map"):
        CausalMap.load(foreign)
    with pytest.raises(CausalMapFormatError, match="no such causal map file"):
        CausalMap.load(tmp_path / "none.npz")
    # A tampered index (an outcome off the map) is refused, not used.
    with np.load(path) as z:
        arrays = {k: z[k] for k in z.files}
    arrays["outcome_keys"] = arrays["outcome_keys"].copy()
    arrays["outcome_keys"][0, 2] = 10_000
    bad = tmp_path / "bad.npz"
    np.savez(bad, **arrays)
    with pytest.raises(CausalMapFormatError, match="outcome_keys names places or options off the map"):
        CausalMap.load(bad)
    arrays["outcome_keys"][0, 2] = 1
    arrays["steps"] = -arrays["steps"]
    np.savez(bad, **arrays)
    with pytest.raises(CausalMapFormatError, match=r"array 'steps' holds counts that are not in 0 \.\."):
        CausalMap.load(bad)
    # values beyond what a life can record, and an unknown member of any size, unread
    for name, value in (("n", 1e308), ("contacts", 1e12)):
        tampered = {**arrays, "steps": np.abs(arrays["steps"])}
        tampered[name] = np.full_like(arrays[name], value)
        np.savez(bad, **tampered)
        with pytest.raises(CausalMapFormatError, match=f"array '{name}' holds counts that are not"):
            CausalMap.load(bad)
    ok = {**arrays, "steps": np.abs(arrays["steps"])}
    ok["contacts"] = ok["n"] + 1
    np.savez(bad, **ok)
    with pytest.raises(CausalMapFormatError, match="more contacts than options executed"):
        CausalMap.load(bad)
    with zipfile.ZipFile(bad) as zf:  # still an archive with the metadata: only checks failed
        assert "metadata.npy" in zf.namelist()


def test_bad_records_and_parameters() -> None:
    cmap = _small()
    with pytest.raises(InvalidArgumentError, match="an outcome needs a next place on the map"):
        cmap.record(0, 0, E, None, 1, False)
    with pytest.raises(InvalidArgumentError, match="no place 99 / option 0 on this map"):
        cmap.record(99, 0, E, 1, 1, False)
    for bad in (0, 1e30, 2.5, True):
        with pytest.raises(InvalidArgumentError, match=r"patience must be an int in 1 \.\. 1000"):
            CausalMap(patience=bad)
    for key in ("contact_cost", "prior", "context_prior", "extent"):
        with pytest.raises(InvalidArgumentError, match=f"{key} must be a number in"):
            CausalMap(**{key: 1e308})
    with pytest.raises(InvalidArgumentError, match="a place .* must be a whole number of grid cells"):
        CausalStrategy(CausalMap(place=1.3))


def _trap() -> Simulator:
    return Simulator(U_TRAP, U_TRAP.start, TRAP_GOAL, np.zeros((0, 2)), np.zeros(0))


def test_the_causal_strategy_gets_out_of_a_u_trap_with_no_map() -> None:
    length = route_length(U_TRAP, U_TRAP.start, TRAP_GOAL)
    sim = _trap()
    out = run_episode(make_agent("compass-guard"), sim, sensing="sensor", max_steps=300,
                    strategy="causal")  # fmt: skip
    assert out.outcome == "success"
    assert out.path_length <= 1.6 * length


def test_a_life_in_the_u_trap_gets_better_and_keeps_its_map() -> None:
    # The same task twice in one life: the second time the agent knows the U's walls
    # and what its options did, so its path is shorter; without a life it is not.
    agent = make_agent("compass-guard")
    origin = np.array(U_TRAP.start, dtype=float)
    first = run_episode(agent, _trap(), sensing="sensor", max_steps=300, strategy="causal",
                      origin=origin)  # fmt: skip
    options = agent.steering.causal.map.n_options
    second = run_episode(agent, _trap(), sensing="sensor", max_steps=300, strategy="causal",
                       origin=origin)  # fmt: skip
    assert first.outcome == second.outcome == "success"
    assert options > 0 and agent.steering.causal.map.n_options > options
    assert second.path_length < 0.8 * first.path_length


def test_a_saved_life_resumes(tmp_path: Path) -> None:
    agent = make_agent("compass-guard")
    origin = np.array(U_TRAP.start, dtype=float)
    first = run_episode(agent, _trap(), sensing="sensor", max_steps=300, strategy="causal",
                      origin=origin)  # fmt: skip
    path = agent.steering.causal.save(tmp_path / "u.npz", world="u-trap")
    resumed = make_agent("compass-guard")
    resumed.steering = Steering()  # type: ignore[attr-defined]
    resumed.steering.causal = CausalStrategy.load(path, world="u-trap")
    second = run_episode(resumed, _trap(), sensing="sensor", max_steps=300, strategy="causal",
                       origin=origin)  # fmt: skip
    assert second.outcome == "success"
    assert second.path_length < 0.8 * first.path_length


def test_files_with_impossible_parameters_or_grids_are_refused(tmp_path: Path) -> None:
    cmap = _small()
    _hand_built(cmap)
    path = cmap.save(tmp_path / "m.npz", occupancy=np.zeros((8, 8)),
                     hits=np.ones((8, 8), dtype=np.int64))  # fmt: skip
    with np.load(path) as z:
        good = {k: z[k] for k in z.files}
    import json

    def with_meta(**params: object) -> Path:
        meta = json.loads(str(good["metadata"][()]))
        meta["params"].update(params)
        bad = tmp_path / "bad.npz"
        np.savez(bad, **{**good, "metadata": np.array(json.dumps(meta))})
        return bad

    for params, message in [
        ({"extent": 1e4, "place": 1e-3}, "places a side; at most 2048"),
        ({"extent": 1e12}, r"extent must be a number in \(0, 10000\]"),
        ({"contact_cost": 1e308}, "contact_cost must be a number in"),
        ({"patience": 1e30}, "patience must be an int in 1 .. 1000"),
        ({"patience": "abc"}, "bad parameters"),
        ({"patience": float("inf")}, "bad parameters"),
    ]:
        with pytest.raises(CausalMapFormatError, match=message):
            CausalMap.load(with_meta(**params))
    bad = tmp_path / "bad.npz"
    np.savez(bad, **{**good, "occupancy": np.array([["a", "b"], ["c", "d"]])})
    with pytest.raises(CausalMapFormatError, match="occupancy is not a finite square grid"):
        CausalMap.load(bad)
    np.savez(bad, **{**good, "hits": -np.ones((8, 8), dtype=np.int64)})
    with pytest.raises(CausalMapFormatError, match="hits are not counts"):
        CausalMap.load(bad)
    # A place the strategy's grid cannot tile: refused by the strategy's loader too.
    odd = CausalMap(extent=80.0, place=0.7)
    odd_path = odd.save(tmp_path / "odd.npz")
    with pytest.raises(CausalMapFormatError, match="whole number of grid cells"):
        CausalStrategy.load(odd_path)


def test_a_resumed_life_keeps_its_learnt_walls(tmp_path: Path) -> None:
    agent = make_agent("compass-guard")
    origin = np.array(U_TRAP.start, dtype=float)
    run_episode(agent, _trap(), sensing="sensor", max_steps=300, strategy="causal", origin=origin)
    causal = agent.steering.causal
    path = causal.save(tmp_path / "u.npz", world="u-trap")
    back = CausalStrategy.load(path, world="u-trap")
    back.reset(type("T", (), {"lifelong": True, "n_rays": 32, "max_range": 10.0,
                              "agent_radius": 0.3})())  # fmt: skip
    assert np.array_equal(back.mapping.occupancy, causal.mapping.occupancy)
    assert np.array_equal(back.mapping.hits, causal.mapping.hits)
    here = origin - origin
    assert np.array_equal(back.mapping.static_reading(here), causal.mapping.static_reading(here))
