"""Closed-form flight (Eqs. 5 to 8 with mass M): limits, inverses, derivatives, reach."""

from __future__ import annotations

import math

import numpy as np
import pytest

from somarm import ballistics


def test_flight_time_is_twice_uy_over_g():
    np.testing.assert_allclose(ballistics.flight_time([0.0, 0.5, 1.0], 0.05), [0.0, 20.0, 40.0])


def test_table_3_hand_values():
    # ux = uy = 1, Fr = 0.1, W = 0, M = 1: T = 40, s_x = (1 - e^-4) / 0.1.
    assert ballistics.landing_x(1.0, 1.0) == pytest.approx((1 - math.exp(-4)) / 0.1, rel=1e-15)
    assert ballistics.landing_x(0.7, 0.0) == 0.0


def test_equals_the_papers_eq_7_for_unit_mass():
    rng = np.random.default_rng(0)
    ux, uy = rng.random(100), rng.uniform(0.01, 1, 100)
    Fr, W, G = rng.uniform(0.01, 0.2, 100), rng.uniform(-3, 0, 100), 0.05
    T = 2 * uy / G
    eq7 = (ux + W) * (np.exp(-Fr * T) - 1) / -Fr - W * T
    np.testing.assert_allclose(ballistics.landing_x(ux, uy, G=G, Fr=Fr, W=W, M=1.0), eq7, rtol=1e-12)


def test_mass_enters_as_the_decay_rate_fr_over_m():
    # Doubling the mass is the same flight as halving the drag.
    a = ballistics.landing_x(0.6, 0.8, Fr=0.2, W=-1.0, M=2.0)
    b = ballistics.landing_x(0.6, 0.8, Fr=0.1, W=-1.0, M=1.0)
    assert a == pytest.approx(b, rel=1e-15)


def test_drag_free_limit_has_no_division_by_zero():
    with np.errstate(all="raise"):
        free = ballistics.landing_x(0.5, 1.0, Fr=0.0, W=-2.0)
        tiny = ballistics.landing_x(0.5, 1.0, Fr=1e-12, W=-2.0)
    T = 40.0
    assert free == pytest.approx((0.5 - 2.0) * T + 2.0 * T, rel=1e-15)  # = ux T: wind cancels
    assert tiny == pytest.approx(free, rel=1e-9)


def test_solution_curve_lands_on_the_target():
    uy = np.linspace(0, 1, 401)
    for params in ({}, {"X": 7.0, "W": -1.5, "Fr": 0.15, "M": 1.3}, {"X": 2.0, "Fr": 0.0}):
        ux = ballistics.solution_ux(uy, **params)
        ok = ~np.isnan(ux)
        assert ok.sum() > 20
        assert ((ux[ok] >= 0) & (ux[ok] <= 1)).all()
        landing_params = {k: v for k, v in params.items() if k != "X"}
        np.testing.assert_allclose(ballistics.landing_x(ux[ok], uy[ok], **landing_params),
                                   params.get("X", 4.0), atol=1e-12)


def test_solution_curve_is_nan_where_out_of_reach():
    assert np.isnan(ballistics.solution_ux(0.0))  # no time in the air
    assert np.isnan(ballistics.solution_ux(0.05, X=4.0))  # too short a flight for ux <= 1
    assert ballistics.solution_ux(0.0, X=0.0) == 0.0


def test_gradient_equals_finite_differences():
    rng = np.random.default_rng(1)
    ux, uy = rng.uniform(0.1, 0.9, 50), rng.uniform(0.1, 0.9, 50)
    params = {"G": 0.05, "Fr": 0.13, "W": -1.2, "M": 1.4}
    d_ux, d_uy = ballistics.landing_gradient(ux, uy, **params)
    h = 1e-6
    fd_ux = (ballistics.landing_x(ux + h, uy, **params) - ballistics.landing_x(ux - h, uy, **params)) / (2 * h)
    fd_uy = (ballistics.landing_x(ux, uy + h, **params) - ballistics.landing_x(ux, uy - h, **params)) / (2 * h)
    np.testing.assert_allclose(d_ux, fd_ux, rtol=1e-6)
    np.testing.assert_allclose(d_uy, fd_uy, rtol=1e-6)


@pytest.mark.parametrize("W", [-3.0, -1.0, 0.0, 0.5, 2.0])
@pytest.mark.parametrize("Fr", [0.0, 0.05, 0.2])
def test_landing_range_equals_a_brute_force_search(W, Fr):
    grid = np.linspace(0, 1, 801)
    UX, UY = np.meshgrid(grid, grid)
    landing = ballistics.landing_x(UX, UY, Fr=Fr, W=W, M=1.3)
    lowest, highest = ballistics.landing_range(Fr=Fr, W=W, M=1.3)
    assert lowest <= landing.min() + 1e-12 and highest >= landing.max() - 1e-12
    assert lowest == pytest.approx(landing.min(), abs=1e-4)
    assert highest == pytest.approx(landing.max(), abs=1e-4)
