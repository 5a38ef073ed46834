"""The throw tasks: simulated landings against Eq. 7, Eq. 8 in simulation, reachable targets."""

from __future__ import annotations

import numpy as np
import pytest

from somarm import tasks
from somarm.tasks import ballistics, flight, launcher
from somarm.tasks.throw import RANGES, TABLE3, ThrowParams, landing_x, simulate_trajectory


def _random_throws(n, seed):
    rng = np.random.default_rng(seed)
    # Continuous u_y (not a 0.05 grid, where flights end on whole steps and hide interpolation error).
    return {"ux": rng.random(n), "uy": rng.random(n), "W": rng.uniform(*RANGES["W"], n),
            "Fr": rng.uniform(*RANGES["Fr"], n), "M": rng.uniform(*RANGES["M"], n)}


def test_simulated_landing_equals_eq_7_over_random_throws():
    throws = _random_throws(3000, 0)
    simulated = landing_x(throws["ux"], throws["uy"], Fr=throws["Fr"], W=throws["W"], M=throws["M"])
    exact = ballistics.landing_x(throws["ux"], throws["uy"], Fr=throws["Fr"], W=throws["W"], M=throws["M"])
    error = np.abs(simulated - exact)
    assert error.max() <= 1e-6, f"largest landing error {error.max():.2e}"
    # Each throw also respects the a-priori bound its step was chosen by (plus rounding).
    k = throws["Fr"] / throws["M"]
    step = flight.step_for(throws["ux"], throws["uy"], throws["W"], k, G=0.05)
    bound = flight.error_bound(throws["ux"], throws["uy"], throws["W"], k, step, G=0.05)
    assert (error <= bound + 1e-11).all()


def test_simulated_landing_with_wind_against_the_thrower_and_no_drag():
    rng = np.random.default_rng(1)
    ux, uy = rng.random(500), rng.random(500)
    for params in ({"W": 0.8, "Fr": 0.1, "M": 1.0}, {"W": -2.0, "Fr": 0.0, "M": 1.5}):
        simulated = landing_x(ux, uy, **params)
        np.testing.assert_allclose(simulated, ballistics.landing_x(ux, uy, **params), rtol=0, atol=1e-6)


def test_a_throw_lands_at_the_same_x_alone_or_in_a_batch():
    throws = _random_throws(700, 2)
    batch = landing_x(throws["ux"], throws["uy"], Fr=throws["Fr"], W=throws["W"], M=throws["M"])
    for i in (0, 123, 699):
        alone = landing_x(throws["ux"][i], throws["uy"][i], Fr=throws["Fr"][i], W=throws["W"][i], M=throws["M"][i])
        assert float(alone) == batch[i]


@pytest.mark.parametrize("params", [TABLE3, ThrowParams(X=7.5, W=-2.0, Fr=0.17, M=1.6)])
def test_points_of_eq_8_land_on_the_target_in_simulation(params):
    uy = np.linspace(0.0, 1.0, 997)
    ux = ballistics.solution_ux(uy, X=params.X, G=params.G, Fr=params.Fr, W=params.W, M=params.M)
    ok = ~np.isnan(ux)
    assert ok.sum() > 50
    simulated = landing_x(ux[ok], uy[ok], params=params)
    np.testing.assert_allclose(simulated, params.X, rtol=0, atol=1e-6)
    task = tasks.make("throw", X=params.X, W=params.W, Fr=params.Fr, M=params.M)
    rewards = task.evaluate(np.array([params.X]), np.stack([ux[ok], uy[ok]], axis=-1))
    assert rewards.min() >= -1e-6


def test_simulate_trajectory_ends_at_the_located_landing_point():
    params = ThrowParams(W=-1.0, Fr=0.15, M=1.2)
    times, xy = simulate_trajectory(0.6, 0.43, params)
    assert times.shape == (len(xy),) and xy.shape[1] == 2
    np.testing.assert_array_equal(xy[0], [0.0, 0.0])
    assert (np.diff(times) > 0).all() and (xy[1:-1, 1] > 0).all() and xy[-1, 1] == 0.0
    assert times[-1] == pytest.approx(ballistics.flight_time(0.43), abs=1e-12)
    assert xy[-1, 0] == pytest.approx(ballistics.landing_x(0.6, 0.43, Fr=0.15, W=-1.0, M=1.2), abs=1e-6)
    assert xy[-1, 0] == float(landing_x(0.6, 0.43, params=params))  # the same flight as the tasks'
    fine_times, _ = simulate_trajectory(0.6, 0.43, params, dt=0.05)
    assert len(fine_times) > len(times)
    with pytest.raises(ValueError, match="dt must be"):
        simulate_trajectory(0.6, 0.43, params, dt=0.0)


@pytest.mark.parametrize("name", ["throw_distance", "throw_wind", "throw_friction", "throw_mass"])
def test_every_sampled_target_is_reachable(name):
    task = tasks.make(name, n_trials=200, seed=4)
    observations = np.concatenate([task.reset() for _ in range(10)]
                                  + [task.sample_observations(np.random.default_rng(0), 5000)])
    assert task.reachable(observations).all()
    c = task.conditions(observations)
    lowest, highest = ballistics.landing_range(G=task.params.G, Fr=c["Fr"], W=c["W"], M=c["M"])
    assert (c["X"] <= highest).all() and (c["X"] >= lowest).all()


def test_table_6_box_holds_unreachable_targets_that_the_sampler_avoids():
    task = tasks.make("throw_friction")
    rng = np.random.default_rng(5)
    box = task.observation_low + (task.observation_high - task.observation_low) * rng.random((20000, 3))
    unreachable = ~task.reachable(box)
    assert 0.0 < unreachable.mean() < 0.05  # a corner: little wind, strong drag, far target
    assert not task.reachable(np.array([[9.0, 0.0, 0.2]]))[0]  # lands near 5.0 at best
    sampled = task.sample_observations(rng, 20000)
    # Uniform over the reachable part: the mean X is the reachable box's mean X.
    assert sampled[:, 0].mean() == pytest.approx(box[~unreachable, 0].mean(), abs=0.1)


def test_distance_task_covers_the_whole_range():
    sampled = tasks.make("throw_distance").sample_observations(np.random.default_rng(6), 20000)
    assert sampled.min() < 0.01 and sampled.max() > 8.99  # Table 3's air reaches 9.82: nothing rejected
    assert sampled.mean() == pytest.approx(4.5, abs=0.1)


@pytest.mark.parametrize("backend", ["mujoco", "analytic"])
def test_punishment_for_throws_below_45_degrees(backend):
    plain = tasks.make("throw_wind", backend=backend)
    punished = tasks.make("throw_wind", backend=backend, punish_low=True)
    observations = np.array([[4.0, -1.0]] * 3)
    actions = np.array([[0.6, 0.3], [0.3, 0.6], [0.5, 0.5]])  # below, above, exactly 45 degrees
    difference = punished.evaluate(observations, actions) - plain.evaluate(observations, actions)
    np.testing.assert_allclose(difference, [-2.0, 0.0, 0.0])


def test_velocities_outside_the_square_are_rejected():
    with pytest.raises(ValueError, match=r"velocities must lie inside \[\(0, 0\), \(1, 1\)\]"):
        landing_x(1.01, 0.5)
    with pytest.raises(ValueError, match="finite"):
        landing_x(np.nan, 0.5)
    with pytest.raises(ValueError, match="backends"):
        landing_x(0.5, 0.5, backend="exact")
    with pytest.raises(ValueError, match="M must be finite and > 0"):
        landing_x([0.5, 0.5], 0.5, M=[1.0, 0.0])
    with pytest.raises(ValueError, match="Fr must be finite and >= 0"):
        landing_x(0.5, 0.5, Fr=-0.1)


def test_params_for_an_observation_drive_the_same_flight_as_the_task():
    task = tasks.make("throw_mass")
    observation = task.sample_observations(np.random.default_rng(8), 1)[0]
    params = ThrowParams(**dict(zip(("X", "W", "Fr", "M"), observation.tolist(), strict=True)))

    _, xy = simulate_trajectory(0.7, 0.6, params)
    reward = task.evaluate(observation, np.array([0.7, 0.6]))
    assert -abs(params.X - xy[-1, 0]) == pytest.approx(float(reward), abs=1e-12)
    _, default = simulate_trajectory(0.7, 0.6)  # no params: Table 3
    assert default[-1, 0] == pytest.approx(ballistics.landing_x(0.7, 0.6), abs=1e-6)


def test_the_dm_env_launcher_lands_where_the_batch_does():
    throws = _random_throws(40, 4)
    batch = landing_x(throws["ux"], throws["uy"], Fr=throws["Fr"], W=throws["W"], M=throws["M"])
    physics = launcher.load_physics()
    for i in range(40):
        c = {k: float(throws[k][i]) for k in ("Fr", "W", "M")}
        physics.set_conditions(**c)
        ux, uy = float(throws["ux"][i]), float(throws["uy"][i])
        launch = physics.launch(ux, uy, step=float(flight.step_for(ux, uy, c["W"], c["Fr"] / c["M"], G=0.05)))
        physics.step()  # the dm_env takes the first step itself
        assert float(physics.fly(previous=launch)[0]) == batch[i]


def test_each_flight_takes_the_fewest_whole_steps_within_the_tolerance():
    throws = _random_throws(2000, 7)
    k = throws["Fr"] / throws["M"]
    step = flight.step_for(throws["ux"], throws["uy"], throws["W"], k, G=0.05)
    T = ballistics.flight_time(throws["uy"], 0.05)
    n = T / step
    np.testing.assert_allclose(n, np.round(n), rtol=0, atol=1e-9)  # the flight ends on a step's end
    assert (flight.error_bound(throws["ux"], throws["uy"], throws["W"], k, step, G=0.05)
            <= flight.DEFAULT_TOLERANCE).all()
    # One step fewer would break the tolerance (or the k h limit), so N is the smallest.
    fewer = np.round(n) - 1
    ok = fewer >= 1
    longer = T[ok] / fewer[ok]
    bound = flight.error_bound(throws["ux"][ok], throws["uy"][ok], throws["W"][ok], k[ok], longer, G=0.05)
    assert ((bound > flight.DEFAULT_TOLERANCE) | (k[ok] * longer > flight.MAX_KH)).all()
    # The dm_env path computes the same step from plain floats.
    for i in range(0, 2000, 97):
        one = flight.step_for(*(float(throws[key][i]) for key in ("ux", "uy", "W")), float(k[i]), G=0.05)
        assert one == step[i]
    # No drag: one step; no flight: a unit step that lands at once.
    assert flight.step_for(np.array([0.5]), np.array([0.4]), 0.0, 0.0, G=0.05)[0] == pytest.approx(16.0)
    assert flight.step_for(np.array([0.5]), np.array([0.0]), 0.0, 0.1, G=0.05)[0] == 1.0


def test_reach_with_only_the_target_varied_is_the_closed_form_range():
    task = tasks.make("throw_distance", n_trials=5, seed=0)
    observations = np.linspace(-1.0, 12.0, 300)[:, None]
    lowest, highest = ballistics.landing_range(G=0.05, Fr=0.1, W=0.0, M=1.0)
    expected = (lowest <= observations[:, 0]) & (observations[:, 0] <= highest)
    for _ in range(2):  # the range is computed once and then reused
        np.testing.assert_array_equal(task.reachable(observations), expected)
    assert 0 < expected.sum() < len(expected)


def _first_reachable_by_hand(task, uniforms: np.ndarray) -> np.ndarray:
    """The sampler spelled out: each row's 16 candidates in turn, judged by landing_range one at a time."""
    d = len(task.varied)
    candidates = task.observation_low + (task.observation_high - task.observation_low) * uniforms.reshape(-1, 16, d)
    chosen = []
    for row in candidates:
        for candidate in row:
            c = task.conditions(candidate)
            lowest, highest = ballistics.landing_range(G=task.params.G, Fr=c["Fr"], W=c["W"], M=c["M"])
            if lowest <= c["X"] <= highest:
                chosen.append(candidate)
                break
        else:  # all 16 missed: the first, with X pulled back to the farthest landing
            c = task.conditions(row[0])
            _, highest = ballistics.landing_range(G=task.params.G, Fr=c["Fr"], W=c["W"], M=c["M"])
            chosen.append(np.concatenate([[min(row[0][0], highest)], row[0][1:]]))
    return np.array(chosen)


@pytest.mark.parametrize("name", ["throw_wind", "throw_friction", "throw_mass"])
def test_observations_are_the_first_reachable_candidate_of_each_row(name):
    task = tasks.make(name, n_trials=3, seed=0)
    uniforms = np.random.default_rng(12).random((400, task.uniform_width))
    d = len(task.varied)
    uniforms[41, :2] = [0.0, 1.0]  # X = 0, no wind: on the lowest bound (the shortest throw)
    if name != "throw_wind":  # throw_wind's box is all in reach (Fr = 0.1 reaches 9.8 in still air)
        # X = 9, no wind, full drag, least mass: out of reach. First candidates of 40 rows, all of one.
        far = np.array([1.0, 1.0, 1.0, 0.0])[:d]
        uniforms[:40, :5 * d] = np.tile(far, 5)
        uniforms[40] = np.tile(far, 16)
    fast = task.observations_from(uniforms)
    np.testing.assert_array_equal(fast, _first_reachable_by_hand(task, uniforms))
    firsts = task.observation_low + (task.observation_high - task.observation_low) * uniforms[:, :d]
    first_kept = (firsts == fast).all(axis=1)
    assert first_kept[41:].mean() > 0.95 and first_kept[41]
    if name != "throw_wind":
        assert not first_kept[:41].any() and 0.0 < fast[40, 0] < 9.0  # all 16 missed: X pulled back
