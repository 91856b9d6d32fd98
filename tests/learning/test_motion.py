"""The learnt model of what moves (copi.learning._motion): perception of the bodies in a
reading, following them, the model learnt from the agent's own walks, its predictions
against the simulator's record, and its file."""

from __future__ import annotations

import json
import math
import re
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from numba import njit

from copi.errors import CapabilitiesFormatError, InvalidArgumentError
from copi.geometry.kernels import sweep_one
from copi.learning import (
    Capabilities,
    MotionModel,
    MotionTracker,
    learn_motion,
    motion_errors,
    motion_tables,
    sample_motion,
)
from copi.learning._motion import (
    _GUIDE,
    N_TURN,
    _draw,
    _draw_row,
    _edge_bin,
    _guides,
    _speed_in,
)
from copi.learning._tracking import HIST, JOIN, _gaps, _median
from copi.world import RangeSensor, World


@pytest.fixture(scope="module")
def model() -> MotionModel:
    return learn_motion(("crowd", "polygon"), worlds=24, steps=150, seed=0)


def test_the_model_learns_the_simulators_motion_without_being_told(model: MotionModel) -> None:
    """Bodies turn by N(0, 0.6) a step (the simulator's rule, never given to the agent):
    the spread learnt with room to spare is within 0.12 of it, and near walls turns are
    broader (bodies a wall stops take a new heading)."""
    sd, broad = model.turn_spread()
    assert abs(sd[-1] - 0.6) < 0.12, sd
    assert sd[0] > 2 * sd[-1]  # with no room ahead: turns of any size
    assert model.stats["examples"] > 500
    prior = model.priors()
    assert 0.55 <= prior["speed"] <= 0.85  # the crowd's discs go 0.8, the polygon's 0.6
    assert abs(prior["turn_sd"] - sd[-1]) < 1e-12


def test_predictions_are_nearer_the_record_than_constant_velocity(model: MotionModel) -> None:
    """On walks in worlds it never saw, the mean of the model's futures of every body
    made out is nearer where the simulator's record puts it 3, 5 and 10 steps on than the
    constant-velocity guess from its last two fits (the stated error: at most 0.85 of
    it at 3 steps, 0.75 at 5, 0.6 at 10)."""
    err = motion_errors(model, ("crowd",), worlds=8, steps=80, seed=1)
    cv, mine = err["constant velocity"], err["model"]
    for h, most in ((3, 0.85), (5, 0.75), (10, 0.6)):
        assert mine[h] < most * cv[h], (h, mine[h], cv[h])


def test_sampled_futures_move_at_the_speed_and_walls_stop_them(model: MotionModel) -> None:
    room = World([[0, 0], [20, 0], [20, 20], [0, 20]])
    bodies = np.array([[10.0, 10.0, 0.0, 1.0, 0.8, 0.5],   # east at 0.8
                       [18.5, 3.0, -0.5, 1.0, 0.6, 0.5]])  # near a wall  # fmt: skip
    f = sample_motion(bodies, np.ascontiguousarray(room.segments), 64, 40, 3,
                      *motion_tables(model), np.zeros((1, 1)), 0.0, 0.0, 1.0)  # fmt: skip
    assert f.shape == (64, 41, 2, 2)
    step = np.hypot(*np.diff(f, axis=1).transpose(3, 0, 1, 2))
    assert (step[..., 0] <= 0.8 + 1e-9).all() and (step[..., 1] <= 0.6 + 1e-9).all()
    assert np.mean(np.isclose(step[..., 0], 0.8)) > 0.8  # the speed kept, but at a wall
    assert (f >= 0.5 - 1e-6).all() and (f <= 19.5 + 1e-6).all()  # inside, by the radius
    same = sample_motion(bodies, np.ascontiguousarray(room.segments), 64, 40, 3,
                         *motion_tables(model), np.zeros((1, 1)), 0.0, 0.0, 1.0)  # fmt: skip
    assert np.array_equal(f, same)  # the same seed, the same futures


def test_futures_far_from_walls_skip_the_sweep_and_stay_the_same(model: MotionModel) -> None:
    """Where the clearance grid says no wall is within a step, a body's move is not swept
    against the walls: the futures are those of sweeping every move (no grid), bit for
    bit, in a room whose walls many futures reach."""
    from copi.geometry import clearance

    room = World([[0, 0], [12, 0], [12, 6], [6, 6], [6, 12], [0, 12]])
    segs = np.ascontiguousarray(room.segments)
    bodies = np.array([[3.0, 3.0, 0.3, 1.0, 0.8, 0.5], [9.0, 2.0, 2.0, 1.0, 1.2, 0.7],
                       [2.0, 10.0, 0.0, 0.0, 0.6, 0.4]])  # fmt: skip
    h = 0.125
    gy, gx = np.mgrid[0:100, 0:100]
    pts = np.column_stack([h * gx.ravel(), h * gy.ravel()])
    clear = np.where(room.contains(pts), clearance(pts, segs), 0.0).reshape(100, 100)
    fast = sample_motion(bodies, segs, 48, 30, 5, *motion_tables(model), clear, 0.0, 0.0, h)
    swept = sample_motion(bodies, segs, 48, 30, 5, *motion_tables(model), np.zeros((1, 1)),
                          0.0, 0.0, 1.0)  # fmt: skip
    assert np.array_equal(fast, swept)
    step = np.hypot(*np.diff(fast, axis=1).transpose(3, 0, 1, 2))
    assert (step < bodies[:, 4] - 1e-6).any()  # walls stopped some moves: both paths ran


@njit(cache=False)
def _every_wall_every_step(bodies, segs, n_samples, horizon, seed, turn_cdf, speed_cdf,  # type: ignore[no-untyped-def]
                           start_cdf, ahead_edges, speed_edges):  # fmt: skip
    """sample_motion as its docstring says it, with nothing spared: every body's every
    step swept against every wall, for the room ahead and for the move."""
    np.random.seed(seed)
    d = bodies.shape[0]
    width = 2.0 * math.pi / turn_cdf.shape[1]
    out = np.empty((n_samples, horizon + 1, d, 2))
    for k in range(d):
        rk = bodies[k, 5]
        for s in range(n_samples):
            x, y = bodies[k, 0], bodies[k, 1]
            if bodies[k, 3] > 0.5:
                h, v = bodies[k, 2], bodies[k, 4]
            else:
                h = 2.0 * math.pi * np.random.random()
                v = _speed_in(speed_edges, _draw(start_cdf))
            out[s, 0, k, 0], out[s, 0, k, 1] = x, y
            for t in range(horizon):
                room = sweep_one(x, y, math.cos(h), math.sin(h), segs, rk)
                b = _draw(turn_cdf[_edge_bin(ahead_edges, room)])
                h += -math.pi + (b + np.random.random()) * width
                if speed_cdf.shape[0] > 1:
                    v = _speed_in(speed_edges, _draw(speed_cdf[_edge_bin(speed_edges, v)]))
                go = sweep_one(x, y, math.cos(h), math.sin(h), segs, rk)
                step = min(v, max(go - 1e-6, 0.0))
                x += step * math.cos(h)
                y += step * math.sin(h)
                out[s, t + 1, k, 0], out[s, t + 1, k, 1] = x, y
    return out


def test_futures_are_those_of_sweeping_every_wall_every_step(model: MotionModel) -> None:
    """The walls a body's sweeps test are only those within the reach that can change
    what they decide, none where the clearance grid says none is near, and its turns are
    drawn through a guide table: the futures are those of
    sweeping every wall at every step, bit for bit, among many walls (pillars and a long
    hall), bodies near and far from them, one faster than the model's fastest."""
    from copi.geometry import clearance

    pillars = [[[x, y], [x + 1, y], [x + 1, y + 1], [x, y + 1]]
               for x in (4, 9, 14, 19, 24) for y in (3, 8)]  # fmt: skip
    hall = World([[0, 0], [30, 0], [30, 12], [0, 12]], holes=pillars)
    segs = np.ascontiguousarray(hall.segments)
    bodies = np.array([[2.0, 6.0, 0.0, 1.0, 0.8, 0.5], [15.5, 6.0, 1.6, 1.0, 2.5, 0.7],
                       [27.0, 10.5, 0.0, 0.0, 0.6, 0.4], [11.0, 1.0, 3.0, 1.0, 1.0, 1.0]])  # fmt: skip
    h = 0.125
    gy, gx = np.mgrid[0:100, 0:244]
    pts = np.column_stack([h * gx.ravel(), h * gy.ravel()])
    clear = np.where(hall.contains(pts), clearance(pts, segs), 0.0).reshape(100, 244)
    tables = motion_tables(model)
    for seed in (1, 2):
        fast = sample_motion(bodies, segs, 32, 30, seed, *tables, clear, 0.0, 0.0, h)
        naive = _every_wall_every_step(bodies, segs, 32, 30, seed, *tables[:5])
        assert np.array_equal(fast, naive)
    step = np.hypot(*np.diff(fast, axis=1).transpose(3, 0, 1, 2))
    assert (step < 0.3).mean() > 0.01  # walls stopped moves: the sweeps mattered


@njit(cache=False)
def _both_draws(cdf, guide, a, seed, n):  # type: ignore[no-untyped-def]
    np.random.seed(seed)
    scan = np.array([_draw(cdf[a]) for _ in range(n)])
    np.random.seed(seed)
    guided = np.array([_draw_row(cdf, a, guide) for _ in range(n)])
    return scan, guided


@settings(max_examples=40, deadline=None)
@given(st.lists(st.integers(0, 5), min_size=2, max_size=40), st.integers(0, 2**31 - 2))
def test_a_guided_draw_is_the_scans_draw(weights: list[int], seed: int) -> None:
    """A bin drawn through the guide table is the one the plain scan of the cumulative
    law finds for the same uniform draw, whatever the law (empty bins, mass in one bin,
    bins finer than the guide's cells), and every bin with mass is drawn."""
    w = np.array(weights, dtype=np.float64)
    w[0] += w.sum() == 0  # a law has some mass
    row = np.cumsum(w) / w.sum()
    uniform = np.arange(1, len(row) + 1) / len(row)
    cdf = np.ascontiguousarray(np.vstack([row, uniform]))
    guide = _guides(cdf)
    assert guide.shape == (2, _GUIDE)
    for a in (0, 1):
        scan, guided = _both_draws(cdf, guide, a, seed, 400)
        assert np.array_equal(scan, guided)
    assert set(_both_draws(cdf, guide, 1, seed, 4000)[1]) == set(range(len(row)))


@settings(max_examples=200, deadline=None)
@given(st.lists(st.floats(0, 3, allow_nan=False), min_size=1, max_size=60))
def test_the_trackers_median_is_numpys(values: list[float]) -> None:
    """The tracker reads its speed and turn medians off lists it keeps sorted: the same
    number as numpy's median of the values in the order they came, to the bit."""
    assert _median(sorted(values)) == np.median(values)


@settings(max_examples=100, deadline=None)
@given(st.lists(st.tuples(st.floats(-2, 2), st.floats(-2, 2)), min_size=1, max_size=20),
       st.floats(0, 2 * math.pi))
def test_hits_are_joined_as_by_math_dist(steps: list[tuple[float, float]], turn: float) -> None:
    """The gaps between hits that cut arcs are math.dist's, to the bit where it matters:
    on either side of JOIN they fall as math.dist's do, steps of exactly JOIN included."""
    d = np.array(steps + [(JOIN * math.cos(turn), JOIN * math.sin(turn))], dtype=np.float64)
    ref = np.array([math.dist((0.0, 0.0), (x, y)) for x, y in d])
    assert np.array_equal(_gaps(d) < JOIN, ref < JOIN)


def test_a_circle_fit_agrees_with_scipys_least_squares() -> None:
    """The tracker's circle of a given radius through noisy arcs: the centre scipy's
    least_squares finds from the same start, to 1e-6."""
    from scipy.optimize import least_squares

    from copi.learning import fit_circle

    rng = np.random.default_rng(4)
    for _ in range(200):
        k = int(rng.integers(3, 12))
        c, r = rng.uniform(-5, 5, 2), float(rng.choice([0.4, 0.6, 0.8, 1.0]))
        ang = rng.uniform(0, 2 * math.pi) + np.linspace(0, rng.uniform(0.3, 2.0), k)
        pts = c + r * np.column_stack([np.cos(ang), np.sin(ang)]) + rng.normal(0, 0.01, (k, 2))
        c0 = c + rng.normal(0, 0.1, 2)
        got, err = fit_circle(pts, r, c0)
        want = least_squares(lambda q, p=pts, r=r: np.hypot(*(p - q).T) - r, c0, xtol=1e-14,
                             ftol=1e-14, gtol=1e-14).x  # fmt: skip
        assert np.allclose(got, want, atol=1e-6), (got, want)
        assert err == pytest.approx(np.mean((np.hypot(*(pts - got).T) - r) ** 2))
    # two points on a line through the start: the least-norm step, no division by zero
    got, _ = fit_circle(np.array([[1.0, 0.0], [2.0, 0.0]]), 0.5, np.array([0.0, 0.0]))
    assert np.isfinite(got).all()
    for pts, r, c0, message in [(np.zeros((0, 2)), 0.5, np.zeros(2), "shape (k >= 1, 2)"),
                                (np.zeros((3, 3)), 0.5, np.zeros(2), "shape (k >= 1, 2)"),
                                (np.full((3, 2), np.nan), 0.5, np.zeros(2), "finite"),
                                (np.zeros((3, 2)), -1.0, np.zeros(2), "positive radius")]:  # fmt: skip
        with pytest.raises(InvalidArgumentError, match=re.escape(message)):
            fit_circle(pts, r, c0)


def test_the_tracker_follows_a_body_and_measures_its_speed() -> None:
    room = World([[0, 0], [30, 0], [30, 30], [0, 30]])
    sensor = RangeSensor()
    me = np.array([5.0, 15.0])
    static = sensor.scan(room, me, np.zeros((0, 2)), np.zeros(0))
    t = MotionTracker(sensor.n_rays, sensor.max_range, speed=0.5, turn_sd=1.0)
    me = np.array([15.0, 15.0])
    static = sensor.scan(room, me, np.zeros((0, 2)), np.zeros(0))
    step = 0.8 / 3.0  # a body circling the agent 3 away, 0.8 a step
    for k in range(8):
        c = me + 3.0 * np.array([[math.cos(step * k), math.sin(step * k)]])
        t.update(sensor.scan(room, me, c, np.array([0.9])), static, me)
    (body,) = t.bodies()
    assert math.dist(body[:2], c[0]) < 0.1 and body[3] == 1.0
    assert abs(t.speed - 6.0 * math.sin(step / 2)) < 0.05
    turn = (body[2] - (step * 6.5 + math.pi / 2) + math.pi) % (2 * math.pi) - math.pi
    assert abs(turn) < 0.15  # the last chord's heading


def test_a_followed_body_keeps_its_id_and_its_last_fits() -> None:
    room = World([[0, 0], [30, 0], [30, 30], [0, 30]])
    sensor = RangeSensor()
    me = np.array([15.0, 15.0])
    static = sensor.scan(room, me, np.zeros((0, 2)), np.zeros(0))
    t = MotionTracker(sensor.n_rays, sensor.max_range, speed=0.5)
    ids, fits = set(), []
    for k in range(7):  # one body walking east, 0.5 a step; a second one from step 5
        c = np.array([[13.5 + 0.5 * k, 17.5]] + ([[17.5, 12.5]] if k >= 5 else []))
        t.update(sensor.scan(room, me, c, np.full(len(c), 0.9)), static, me)
        tracks = t.tracks()
        assert len(tracks) == len(t.bodies()) == len(c)
        for (_, last, rays), body in zip(tracks, t.bodies(), strict=True):
            assert np.array_equal(last[-1], body[:2]) and rays >= 1
        first = min(tracks, key=lambda tr: math.dist(tr[1][-1], c[0]))
        ids.add(first[0])
        fits.append(first[1][-1])
    assert len(ids) == 1  # followed all along: one id
    (_, last, _), other = sorted(t.tracks(), key=lambda tr: tr[1][-1][1], reverse=True)
    assert len(last) == HIST and np.array_equal(last, np.array(fits[-HIST:]))
    assert len(other[1]) == 2 and other[0] not in ids  # seen twice, an id of its own


def _side_by_side(rng: np.random.Generator, me: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two discs side by side across the agent's view, 1.8 to 4 from it."""
    d, a = rng.uniform(1.8, 4.0), rng.uniform(0, 2 * math.pi)
    radii = rng.uniform(0.5, 1.0, 2)
    c1 = me + d * np.array([math.cos(a), math.sin(a)])
    b = a + rng.uniform(-1, 1) + math.pi / 2
    c2 = c1 + (radii.sum() + rng.uniform(0.05, 0.6)) * np.array([math.cos(b), math.sin(b)])
    return np.array([c1, c2]), radii


def test_split_arcs_make_out_discs_side_by_side_and_leave_a_lone_disc_alone() -> None:
    """Two discs whose hits form one arc: one circle is placed between them (its worst
    error over the two discs 1.2 in the median of 200 such scenes); cut into runs, each
    disc is made out (median worst error 0.15 when written). A lone disc, or discs apart,
    are made out alike either way, to the bit."""
    room = World([[0, 0], [20, 0], [20, 20], [0, 20]])
    sensor, me = RangeSensor(), np.array([10.0, 10.0])
    static = sensor.scan(room, me, np.zeros((0, 2)), np.zeros(0))
    rng = np.random.default_rng(1)
    one, cut = [], []
    while len(one) < 200:
        centres, radii = _side_by_side(rng, me)
        if math.dist(centres[1], me) < radii[1] + 0.5:
            continue
        ranges = sensor.scan(room, me, centres, radii)
        c0, _, _ = MotionTracker(32, 10.0).detect(ranges, static, me)
        if len(c0) != 1:
            continue
        c1, _, rays = MotionTracker(32, 10.0, split=True).detect(ranges, static, me)
        assert rays.sum() == MotionTracker(32, 10.0).detect(ranges, static, me)[2].sum()
        one.append(max(np.hypot(*(c0 - c).T).min() for c in centres))
        cut.append(max(np.hypot(*(c1 - c).T).min() for c in centres))
    assert np.median(one) > 0.8 and np.median(cut) < 0.3
    for _ in range(100):  # a lone disc and two far apart: the same bodies
        n = int(rng.integers(1, 3))
        centres = me + rng.uniform(-6, 6, (n, 2))
        radii = rng.uniform(0.4, 1.0, n)
        if n == 2 and math.dist(*centres) < radii.sum() + 2.0:
            continue
        if (np.hypot(*(centres - me).T) < radii + 0.5).any():
            continue
        ranges = sensor.scan(room, me, centres, radii)
        plain = MotionTracker(32, 10.0).detect(ranges, static, me)
        split = MotionTracker(32, 10.0, split=True).detect(ranges, static, me)
        for x, y in zip(plain, split, strict=True):
            np.testing.assert_array_equal(x, y)


def test_a_capabilities_file_keeps_its_model(predictive_caps: Path, tmp_path: Path) -> None:
    caps = Capabilities.load(predictive_caps)
    assert caps.motion_model is not None
    caps.save(tmp_path / "again.npz")
    back = Capabilities.load(tmp_path / "again.npz")
    assert back.equals(caps) and back.motion_model is not None
    assert np.array_equal(back.motion_model.turn_counts, caps.motion_model.turn_counts)
    assert (tmp_path / "again.npz").read_bytes() == predictive_caps.read_bytes()


def _tampered(src: Path, dst: Path, change) -> Path:  # type: ignore[no-untyped-def]
    from copi._files import write_npz

    with np.load(src, allow_pickle=False) as z:
        arrays = {k: z[k] for k in z.files}
    meta = json.loads(str(arrays["metadata"][()]))
    change(arrays, meta)
    arrays["metadata"] = np.array(json.dumps(meta))
    return write_npz(dst, arrays)


@pytest.mark.parametrize(("change", "message"), [
    (lambda a, m: a.pop("motion_turn"), "the motion model is incomplete"),
    (lambda a, m: m.pop("motion_model"), "the motion model is incomplete"),
    (lambda a, m: a.update(motion_turn=a["motion_turn"][:, :10]),
     "motion_turn must have shape (4, 36)"),
    (lambda a, m: a.update(motion_speed=np.full((16, 16), np.nan)),
     "member 'motion_speed' holds NaN or infinite values"),
    (lambda a, m: a.update(motion_start=-a["motion_start"] - 1), "must hold counts in 0 .. 1e9"),
    (lambda a, m: m["motion_model"].update(radius=1e9), "radius must be in 0.05 .. 5"),
    (lambda a, m: m["motion_model"].update(radius="big"), "radius must be a number"),
])  # fmt: skip
def test_a_tampered_model_is_refused(change, message: str, predictive_caps: Path,
                                     tmp_path: Path) -> None:  # fmt: skip
    bad = _tampered(predictive_caps, tmp_path / "bad.npz", change)
    with pytest.raises(CapabilitiesFormatError, match=message.replace("(", r"\(").replace(
            ")", r"\)")):  # fmt: skip
        Capabilities.load(bad)


def test_bad_tables_and_arguments_are_refused(model: MotionModel) -> None:
    with pytest.raises(InvalidArgumentError, match="kind must be robust or empirical"):
        model.turn_p("psychic")
    with pytest.raises(InvalidArgumentError, match="speeds must be keep or drawn"):
        motion_tables(model, speeds="fast")
    with pytest.raises(InvalidArgumentError, match="speed must be a positive number"):
        MotionTracker(32, 10.0, speed=float("nan"))
    with pytest.raises(InvalidArgumentError, match="split must be True or False"):
        MotionTracker(32, 10.0, split="no")
    ranges = np.full(32, 10.0)
    for where in ([np.nan, 1.0], [1.0, 2.0, 3.0]):
        with pytest.raises(InvalidArgumentError, match="position must be two finite numbers"):
            MotionTracker(32, 10.0).update(ranges, ranges, where)


def test_a_seventh_column_draws_a_body_s_first_turn_from_the_row_it_names(
    model: MotionModel,
) -> None:
    """A row of ``turn_cdf`` named by a body's seventh column (a law of how far its
    measured heading may be off) gives its first turn, the room's rows every later one;
    -1, or no seventh column, is the room's law, bit for bit."""
    room = World([[0, 0], [40, 0], [40, 40], [0, 40]])
    segs = np.ascontiguousarray(room.segments)
    turn, *rest = motion_tables(model)
    quarter = np.zeros(N_TURN)
    quarter[(3 * N_TURN) // 4] = 1.0  # every turn in the bin just past +90 degrees
    tables = (np.ascontiguousarray(np.vstack([turn, np.cumsum(quarter)])), *rest)
    six = np.array([[20.0, 20.0, 0.0, 1.0, 0.8, 0.5], [10.0, 30.0, 1.0, 1.0, 0.8, 0.5]])
    seven = np.column_stack([six, [len(turn), -1]])
    f = sample_motion(seven, segs, 64, 10, 3, *tables, np.zeros((1, 1)), 0.0, 0.0, 1.0)
    first = np.arctan2(*(f[:, 1, 0] - f[:, 0, 0])[:, ::-1].T)
    assert np.all((first > math.pi / 2 - 1e-9) & (first < math.pi / 2 + 2 * math.pi / N_TURN))
    later = np.diff(np.unwrap(np.arctan2(*np.diff(f[:, :, 0], axis=1)[..., ::-1].transpose(2, 0, 1)),
                              axis=1), axis=1)  # fmt: skip
    assert np.abs(later).max() < math.pi and np.mean(np.abs(later) > 1.0) < 0.2  # the room's
    base = sample_motion(np.ascontiguousarray(six), segs, 64, 10, 3, *tables, np.zeros((1, 1)),
                         0.0, 0.0, 1.0)  # fmt: skip
    assert np.array_equal(f[:, :, 1], base[:, :, 1])  # -1: the room's law
    unknown = seven.copy()
    unknown[0, 3] = 0.0  # a body with no heading starts anywhere: its column is not read
    g = sample_motion(unknown, segs, 64, 10, 3, *tables, np.zeros((1, 1)), 0.0, 0.0, 1.0)
    h = sample_motion(np.ascontiguousarray(unknown[:, :6]), segs, 64, 10, 3, *tables,
                      np.zeros((1, 1)), 0.0, 0.0, 1.0)  # fmt: skip
    assert np.array_equal(g, h)
