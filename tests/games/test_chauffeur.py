"""The homicidal chauffeur against Isaacs (tests/data/homicidal_chauffeur)."""

from __future__ import annotations

import csv
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.integrate import solve_ivp

from copi.errors import InvalidArgumentError
from copi.games import (
    ChauffeurGame,
    ChauffeurParams,
    Pursuer,
    critical_beta,
    play_open,
    pursuer_step,
)
from tests.common import DATA as TEST_DATA

DATA = TEST_DATA / "homicidal_chauffeur" / "critical_beta.csv"


def _table() -> dict[float, float]:
    with open(DATA) as fh:
        return {
            float(r["gamma"]): float(r["beta_crit_numeric_barrier_trace"])
            for r in csv.DictReader(fh)
        }


def test_critical_beta_matches_the_barrier_trace() -> None:
    for gamma, beta in _table().items():
        assert critical_beta(gamma) == pytest.approx(beta, abs=1e-7)


STARTS = [
    (r * math.cos(a), r * math.sin(a))
    for r in (2.0, 4.0)
    for a in np.linspace(0, 2 * math.pi, 6, endpoint=False)
]


def _crit(gamma: float) -> float:
    return _table()[gamma]


@pytest.mark.parametrize("gamma", [0.3, 0.5, 0.7, 0.9])
def test_above_the_barrier_the_car_always_captures(gamma: float) -> None:
    beta = _crit(gamma) + 0.05
    p = ChauffeurParams(evader_speed=gamma, pursuer_speed=1.0, turn_radius=1.0, capture_radius=beta)
    results = [play_open(p, s, [0, 0], math.pi / 2, horizon=120, dt=0.02) for s in STARTS]
    assert all(r.captured for r in results)


@pytest.mark.parametrize("gamma", [0.5, 0.7, 0.9])
def test_below_the_barrier_the_evader_escapes(gamma: float) -> None:
    # (gamma 0.3 is left out: beta_crit(0.3) = 0.045 < 0.05, no beta to test below it.)
    beta = _crit(gamma) - 0.05
    p = ChauffeurParams(evader_speed=gamma, pursuer_speed=1.0, turn_radius=1.0, capture_radius=beta)
    results = [play_open(p, s, [0, 0], math.pi / 2, horizon=80, dt=0.02) for s in STARTS]
    assert not any(r.captured for r in results)
    assert min(r.closest for r in results) > beta


@pytest.mark.parametrize("gamma", [0.3, 0.5, 0.7, 0.9])
@pytest.mark.parametrize("d", [3.0, 7.5])
def test_dead_ahead_capture_time(gamma: float, d: float) -> None:
    p = ChauffeurParams(evader_speed=gamma, pursuer_speed=1.0, turn_radius=1.0, capture_radius=0.2)
    straight = lambda e, car, heading, params: np.array([0.0, 1.0])  # noqa: E731
    r = play_open(p, [0, d], [0, 0], math.pi / 2, horizon=200, dt=0.05, evader_policy=straight)
    assert r.captured
    assert r.capture_time == pytest.approx((d - 0.2) / (1 - gamma), rel=0.01)


@settings(max_examples=60, deadline=None)
@given(u=st.floats(-1, 1), heading=st.floats(0, 2 * math.pi), dt=st.floats(0.01, 2.0))
def test_the_car_drives_exact_arcs(u: float, heading: float, dt: float) -> None:
    p = ChauffeurParams(turn_radius=3.0)
    car = Pursuer(np.zeros(2), heading, p)
    disp = car.arc(u, dt)
    dist = p.pursuer_speed * dt
    assert car.heading - heading == pytest.approx(u * dist / p.turn_radius, abs=1e-12)
    # the chord of an arc of length dist and radius R/|u|
    if abs(u) > 1e-9:
        rho = p.turn_radius / abs(u)
        chord = 2 * rho * math.sin(dist / (2 * rho))
    else:
        chord = dist
    assert np.linalg.norm(disp) == pytest.approx(chord, rel=1e-9, abs=1e-12)


@pytest.mark.parametrize("seed", range(8))
def test_world_frame_simulation_solves_the_papers_relative_equations(seed: int) -> None:
    """§IV gives the evader relative to the car: x' = V_e sin(phi) - V_p y u / R,
    y' = V_e cos(phi) - V_p + V_p x u / R. Integrate them (tight tolerances) and compare
    with copi's world-frame steps mapped into the car's frame, x to its right and y along
    its heading, with the paper's u = -u of copi (copi's u > 0 turns left). The evader
    keeps a world direction a, so its paper control is phi(t) = heading(t) - a."""
    rng = np.random.default_rng(seed)
    params = ChauffeurParams(capture_radius=1e-3, substeps=7)
    vp, ve, r = params.pursuer_speed, params.evader_speed, params.turn_radius
    u = float(rng.choice([-1.0, 1.0])) if seed < 2 else float(rng.uniform(-1, 1))
    a, h0 = rng.uniform(-np.pi, np.pi, 2)
    car = Pursuer(rng.uniform(-5, 5, 2), h0, params)
    e = car.position + rng.uniform(8, 15) * np.array([np.cos(a + 1.0), np.sin(a + 1.0)])
    de = ve * np.array([np.cos(a), np.sin(a)])  # one time step of the evader
    frame = [(car.position.copy(), car.heading, e.copy())]
    for _ in range(3):
        tau, _ = pursuer_step(car, e, de, np.zeros((0, 4)), 0.5, control=u)
        assert tau == math.inf
        e = e + de
        frame.append((car.position.copy(), car.heading, e.copy()))

    def car_frame(p, h, ev):
        d = ev - p
        return np.array([d @ [np.sin(h), -np.cos(h)], d @ [np.cos(h), np.sin(h)]])

    u_paper = -u

    def paper(t, xy):
        phi = h0 + u * vp * t / r - a
        x, y = xy
        return [
            ve * np.sin(phi) - vp * y * u_paper / r,
            ve * np.cos(phi) - vp + vp * x * u_paper / r,
        ]

    sol = solve_ivp(
        paper, (0, 3), car_frame(*frame[0]), t_eval=[0, 1, 2, 3], rtol=1e-11, atol=1e-11,
        method="DOP853",
    )  # fmt: skip
    for k in range(4):
        np.testing.assert_allclose(sol.y[:, k], car_frame(*frame[k]), atol=1e-8)
        assert frame[k][1] == pytest.approx(h0 + u * vp * k / r, abs=1e-12)


def test_games_are_reproducible_and_walls_stop_the_car() -> None:
    a = ChauffeurGame.draw(3, 1, dynamic=True)
    b = ChauffeurGame.draw(3, 1, dynamic=False)
    assert np.array_equal(a.sim.position, b.sim.position)
    assert np.array_equal(a.car.position, b.car.position)
    assert len(b.sim.radii) == 0 and len(a.sim.radii) >= 10
    for _ in range(150):
        if a.step(a.evader_wish()):
            break
        assert a.world.clearance(a.car.position) >= 0.3 - 1e-6
        assert a.world.contains(a.car.position)


def test_bad_parameters() -> None:
    with pytest.raises(InvalidArgumentError, match="need 0 < evader_speed < pursuer_speed"):
        ChauffeurParams(evader_speed=2.0, pursuer_speed=1.0)
    with pytest.raises(InvalidArgumentError, match="gamma"):
        critical_beta(1.0)


