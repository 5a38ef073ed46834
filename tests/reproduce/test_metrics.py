import numpy as np
import pytest

from somarm.reproduce import metrics

LINE5 = np.column_stack([np.arange(5), np.zeros(5)])


def test_grid_distances_chebyshev():
    grid = np.array([[0, 0], [0, 1], [1, 1], [2, 3]])
    d = metrics.chebyshev_distances(grid)
    assert d[0, 2] == 1 and d[0, 3] == 3 and d[1, 3] == 2
    np.testing.assert_array_equal(d, d.T)


def test_topographic_error_ordered_and_twisted_maps():
    ordered = np.linspace(0, 1, 5)[:, None]
    samples = np.linspace(0, 1, 101)[:, None]
    assert metrics.topographic_error(ordered, LINE5, samples) == 0.0
    twisted = ordered[[0, 3, 2, 1, 4]]
    assert metrics.topographic_error(twisted, LINE5, samples) > 0.3


def test_nearest_is_neighbour():
    ordered = np.linspace(0, 1, 5)[:, None]
    assert metrics.nearest_is_neighbour(ordered, LINE5) == 1.0
    shuffled = ordered[[0, 2, 4, 1, 3]]
    assert metrics.nearest_is_neighbour(shuffled, LINE5) == 0.0


def test_greedy_jumps_counts_neighbour_pairs():
    jumps = metrics.greedy_jumps(np.array([0, 1, 1, 4, 3]), LINE5, LINE5)
    np.testing.assert_array_equal(jumps, [1, 0, 3, 1])


def test_distance_to_polyline_and_nan_split():
    line = np.array([[0.0, 0.0], [1.0, 0.0], [np.nan, np.nan], [1.0, 1.0], [2.0, 1.0]])
    points = np.array([[0.5, 0.5], [1.5, 1.0], [3.0, 1.0]])
    np.testing.assert_allclose(metrics.distance_to_polyline(points, line), [0.5, 0.0, 1.0])


def test_spacing_cv_equal_and_unequal():
    assert metrics.spacing_cv([0, 1, 2, 3]) == pytest.approx(0.0)
    assert metrics.spacing_cv([0, 1, 3, 7]) > 0.5


def test_steps_to_level_and_spearman():
    steps = np.array([100, 200, 300, 400])
    assert metrics.steps_to_level(steps, np.array([3.0, 2.0, 0.5, 0.4]), 1.0) == 300
    assert np.isnan(metrics.steps_to_level(steps, np.array([3.0, 2.0, 2.0, 2.0]), 1.0))
    assert metrics.spearman(np.arange(10), np.arange(10) ** 2) == pytest.approx(1.0)
    assert metrics.spearman(np.arange(10), -np.arange(10.0)) == pytest.approx(-1.0)


def test_centred_mean_does_not_lag():
    step = np.r_[np.ones(10), np.zeros(10)][:, None]
    centred = metrics.centred_mean(step, 2)[:, 0]
    np.testing.assert_allclose(centred[:8], 1.0)
    assert centred[9] == pytest.approx(0.6) and centred[10] == pytest.approx(0.4)
    np.testing.assert_allclose(centred[12:], 0.0)
    np.testing.assert_allclose(metrics.centred_mean(np.arange(5.0), 1), [0.5, 1, 2, 3, 3.5])


def test_a_failed_trial_is_above_twice_the_median():
    errors = np.array([0.010, 0.011, 0.012, 0.013, 0.0239, 0.0241, 0.268])  # median 0.013: threshold 0.026
    np.testing.assert_array_equal(metrics.failed_trials(errors), [0, 0, 0, 0, 0, 0, 1])
    # An absolute 0.05 would pass a trial at 4x the median of a run whose trials sit near 0.01 ...
    assert not metrics.failed_trials(np.array([0.010, 0.010, 0.010, 0.045]))[:3].any()
    assert metrics.failed_trials(np.array([0.010, 0.010, 0.010, 0.045]))[3]
    # ... and fail every trial of a task whose errors are all larger: relative to the median, none fails.
    assert not metrics.failed_trials(np.array([0.30, 0.32, 0.35, 0.31])).any()


def test_failed_trials_threshold_is_strict_and_uses_the_median_not_the_mean():
    errors = np.array([1.0, 1.0, 1.0, 2.0, 100.0])  # mean 21: a mean-based threshold would pass 100
    np.testing.assert_array_equal(metrics.failed_trials(errors), [0, 0, 0, 0, 1])  # 2.0 is not above 2 x 1
    np.testing.assert_array_equal(metrics.failed_trials(errors, factor=1.5), [0, 0, 0, 1, 1])


@pytest.mark.parametrize("errors, factor", [([], 2.0), ([1.0, np.nan], 2.0), ([[1.0]], 2.0), ([1.0], 1.0)])
def test_failed_trials_refuses_bad_input(errors, factor):
    with pytest.raises(ValueError, match="errors|factor"):
        metrics.failed_trials(np.array(errors), factor)


def test_the_reports_count_failed_trials_by_the_one_definition():
    from somarm.reproduce import beyond

    errors = np.array([0.010, 0.011, 0.012, 0.013, 0.040])  # 0.040 is 3.3x the median: failed
    said = beyond._outliers(errors)
    assert "1 of 5 trials failed (above twice the median): trial 4" in said
    assert "no trial failed" in beyond._outliers(np.array([0.010, 0.011, 0.012, 0.013, 0.023]))


def test_edge_share_counts_units_within_the_width_of_a_lower_bound():
    low = np.array([-np.pi, -np.pi])
    piled = np.column_stack([np.full(4, -np.pi + 0.01), np.linspace(-1, 1, 4)])  # every unit at theta1's edge
    spread = np.column_stack([np.linspace(-2, 2, 4), [-np.pi + 0.05, 0.0, 1.0, 2.0]])  # one unit at theta2's edge
    far = np.column_stack([np.full(4, -np.pi + 0.07), np.zeros(4)])  # just outside 0.06 rad
    np.testing.assert_allclose(metrics.edge_share(np.stack([piled, spread, far]), low), [1.0, 0.25, 0.0])
    assert metrics.edge_share(far[None], low, width=0.08)[0] == 1.0
    at_high = -piled  # every unit within 0.01 of +pi in theta1
    assert metrics.edge_share(at_high[None], low)[0] == 0.0
    assert metrics.edge_share(at_high[None], low, -low)[0] == 1.0
