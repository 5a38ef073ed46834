"""Closed-form flight (Eqs. 5 to 8 with mass M): limits, inverses, derivatives, reach."""

from __future__ import annotations

import math

import numpy as np
import pytest

from somarm.tasks import ballistics


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


def _counting_landing_range(monkeypatch) -> list[int]:
    """Make ``landing_range`` count the elements it is asked about (within_reach's fallback)."""
    sizes: list[int] = []
    original = ballistics.landing_range

    def counted(**params):
        sizes.append(int(np.broadcast_shapes(*(np.shape(v) for v in params.values()))[0]))
        return original(**params)

    monkeypatch.setattr(ballistics, "landing_range", counted)
    return sizes


def test_within_reach_answers_as_landing_range_on_and_near_the_bounds(monkeypatch):
    rng = np.random.default_rng(11)
    n = 4000
    # Beyond Table 6's box: wind from behind (W > 0) puts the extremum inside [0, 1]; no drag.
    Fr = np.where(rng.random(n) < 0.1, 0.0, rng.uniform(0.0, 0.3, n))
    W, M = rng.uniform(-4.0, 3.0, n), rng.uniform(0.5, 2.5, n)
    lowest, highest = ballistics.landing_range(Fr=Fr, W=W, M=M)
    bound = np.where(rng.random(n) < 0.5, lowest, highest)
    ulps = rng.integers(-3, 4, n) * np.spacing(bound)
    # The undecided band is 1e-9 (1 + size of the terms) wide, size < 600 here: X within 1e-10
    # of a bound falls in it, X 1e-5 away does not.
    offsets = [1e-12, -1e-12, 1e-10, -1e-10, 1e-5, -1e-5, 1e-3, -1e-3]
    X = np.concatenate([bound, bound + ulps, *(bound + o for o in offsets), rng.uniform(-20.0, 20.0, n),
                        [np.nan, np.inf, -np.inf]])
    params = {key: np.concatenate([np.tile(v, len(offsets) + 3), v[:3]]) for key, v in
              (("Fr", Fr), ("W", W), ("M", M))}
    lowest, highest = ballistics.landing_range(**params)
    expected = (lowest <= X) & (X <= highest)
    sizes = _counting_landing_range(monkeypatch)
    np.testing.assert_array_equal(ballistics.within_reach(X, **params), expected)
    # Points on a bound and within 1e-10 of it (and NaN) were left to landing_range, the rest not.
    assert len(sizes) == 1 and 6 * n < sizes[0] <= 6 * n + 10
    assert 0.2 < expected.mean() < 0.8


def test_within_reach_broadcasts_and_uses_no_fallback_away_from_the_bounds(monkeypatch):
    X = np.linspace(-2.0, 12.0, 15)[:, None] + 0.01  # none on a bound (0 is the lowest of some)
    W = np.array([-3.0, -1.0, 0.0, 0.7])
    lowest, highest = ballistics.landing_range(Fr=0.15, W=W, M=1.4)
    sizes = _counting_landing_range(monkeypatch)
    reach = ballistics.within_reach(X, Fr=0.15, W=W, M=1.4)
    assert reach.shape == (15, 4) and sizes == []
    np.testing.assert_array_equal(reach, (lowest <= X) & (X <= highest))
    assert ballistics.within_reach(4.0).shape == () and ballistics.within_reach(4.0)
    assert not ballistics.within_reach(30.0, W=0.0, Fr=0.2)
