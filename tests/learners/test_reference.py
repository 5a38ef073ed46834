"""The batched, compiled SOM-Q equals the line-by-line reference of the paper's ten steps EXACTLY."""

import dataclasses

import numpy as np
import pytest
from somq_cases import BOUNDS
from somq_cases import arc as _arc
from somq_cases import small_config as _config

from somarm.learners.reference import ReferenceSOMQ
from somarm.learners.somq import SOMQLearner


def _run_both(config, *, n_trials=3, n_steps=150, seed=11, bounds=BOUNDS):
    batched = SOMQLearner(config, n_trials=n_trials, seed=seed, **bounds)
    references = [ReferenceSOMQ(config, seed=seed, trial_id=i, **bounds) for i in range(n_trials)]
    rng = np.random.default_rng(123)
    observations = rng.uniform([0, -1], [1, 1], (n_trials, 2))
    for step in range(n_steps):
        actions = batched.act(observations)
        expected = np.stack([ref.act(observations[i]) for i, ref in enumerate(references)])
        np.testing.assert_array_equal(actions, expected, err_msg=f"actions differ at step {step}")
        rewards = -np.abs(actions[:, 0] - observations[:, 0]) - np.abs(actions[:, 1] + observations[:, 1])
        next_observations = rng.uniform([0, -1], [1, 1], (n_trials, 2))
        terminal = rng.random(n_trials) < 0.3
        batched.learn(rewards, next_observations, terminal)
        for i, ref in enumerate(references):
            ref.learn(rewards[i], next_observations[i], bool(terminal[i]))
        observations = next_observations
    return batched, references


@pytest.mark.parametrize("input_shape", [(6,), (3, 4)], ids=["1d", "2d"])
@pytest.mark.parametrize("neighbourhood_q", [True, False], ids=["NL", "noNL"])
@pytest.mark.parametrize("gamma", [0.0, 0.9], ids=["immediate", "delayed"])
def test_batched_equals_reference_exactly(input_shape, neighbourhood_q, gamma):
    batched, references = _run_both(_config(input_shape, neighbourhood_q, gamma))
    for i, ref in enumerate(references):
        np.testing.assert_array_equal(batched.input_weights[i], ref.input_weights)
        np.testing.assert_array_equal(batched.action_weights[i], ref.action_weights)
        np.testing.assert_array_equal(batched.q[i], ref.q)
    assert batched.t == references[0].t == 150
    # The run must have exercised learning: Q moved and the maps left their initial places.
    assert np.abs(batched.q).max() > 0.1


def test_gaussian_noise_equals_reference_exactly():
    batched, references = _run_both(_config((5,), True, 0.5, noise="gaussian"), n_steps=80)
    for i, ref in enumerate(references):
        np.testing.assert_array_equal(batched.action_weights[i], ref.action_weights)
        np.testing.assert_array_equal(batched.q[i], ref.q)


def test_reference_keeps_actions_inside_bounds_and_copies_the_unit():
    config = _config((4,), True, 0.0)
    ref = ReferenceSOMQ(config, seed=0, trial_id=0, **BOUNDS)
    before = ref.action_weights.copy()
    actions = np.stack([ref.act([0.5, 0.0]) for _ in range(50)])  # no learn: the maps must not move
    np.testing.assert_array_equal(ref.action_weights, before)
    assert (actions >= BOUNDS["action_low"]).all() and (actions <= BOUNDS["action_high"]).all()
    # epsilon = 0.4 on a box of width 2 to 4: some perturbations really move away from the units.
    assert np.abs(actions[:, None, :] - before[None]).min(axis=(1, 2)).max() > 1e-3


def test_relative_epsilon_equals_reference_exactly():
    config = dataclasses.replace(_config((3, 2), True, 0.0), epsilon_relative=True)
    batched, references = _run_both(config, n_steps=80)
    for i, ref in enumerate(references):
        np.testing.assert_array_equal(batched.action_weights[i], ref.action_weights)
        np.testing.assert_array_equal(batched.q[i], ref.q)


#: Dimensions 0 and 2 as circles (their low and high one point), dimension 1 a plain interval.
PERIODIC = [True, False, True]


@pytest.mark.parametrize("noise", ["uniform", "gaussian"])
def test_periodic_actions_equal_reference_exactly(noise):
    config = dataclasses.replace(_config((5,), True, 0.0, noise=noise), periodic_actions=True)
    batched = SOMQLearner(config, n_trials=3, seed=2, action_periodic=PERIODIC, **BOUNDS)
    references = [ReferenceSOMQ(config, seed=2, trial_id=i, action_periodic=PERIODIC, **BOUNDS) for i in range(3)]
    rng = np.random.default_rng(5)
    wrapped = 0
    for step in range(150):
        observations = rng.uniform([0, -1], [1, 1], (3, 2))
        actions = batched.act(observations)
        expected = np.stack([ref.act(observations[i]) for i, ref in enumerate(references)])
        np.testing.assert_array_equal(actions, expected, err_msg=f"actions differ at step {step}")
        # Best near the top edge of dimension 0 (0.95 of [-1, 1]) and the bottom of dimension 2: the
        # perturbations and the units go round the edges.
        wrapped += int((actions[:, 0] < -0.5).sum() + (actions[:, 2] > 1.0).sum())
        rewards = (-np.abs(_arc(actions[:, 0] - 0.95, 2.0)) - np.abs(actions[:, 1] - observations[:, 0])
                   - np.abs(_arc(actions[:, 2] + 1.9, 4.0)))
        batched.learn(rewards)
        for i, ref in enumerate(references):
            ref.learn(rewards[i])
    for i, ref in enumerate(references):
        np.testing.assert_array_equal(batched.action_weights[i], ref.action_weights)
        np.testing.assert_array_equal(batched.q[i], ref.q)
    assert wrapped > 20  # many actions came out across an edge


@pytest.mark.parametrize("response", ["winner", "interpolated"])
def test_optimistic_start_and_grid_actions_equal_reference_exactly(response):
    # Two action dimensions on a 3 x 3 action map spread over the box, every Q starting above any return.
    bounds = dict(BOUNDS, action_low=[-1.0, 0.0], action_high=[1.0, 1.0])
    config = dataclasses.replace(_config((3, 2), True, 0.9), action_shape=(3, 3), action_init="grid", q_init=2.0,
                                 response=response)
    fresh = SOMQLearner(config, n_trials=3, seed=11, **bounds)
    np.testing.assert_array_equal(fresh.action_weights[2], [[-1, 0], [-1, 0.5], [-1, 1], [0, 0], [0, 0.5], [0, 1],
                                                            [1, 0], [1, 0.5], [1, 1]])
    assert (fresh.q == 2.0).all()
    batched, references = _run_both(config, bounds=bounds, n_steps=100)
    for i, ref in enumerate(references):
        np.testing.assert_array_equal(batched.input_weights[i], ref.input_weights)
        np.testing.assert_array_equal(batched.action_weights[i], ref.action_weights)
        np.testing.assert_array_equal(batched.q[i], ref.q)
    assert batched.q.min() < 1.0  # the optimistic values were learned down


def test_a_grid_over_part_of_the_box_equals_reference_exactly():
    bounds = dict(BOUNDS, action_low=[-1.0, 0.0], action_high=[1.0, 1.0])
    config = dataclasses.replace(_config((3, 2), True, 0.9), action_shape=(3, 3), action_init="grid",
                                 grid_span=0.5, q_init=2.0)
    np.testing.assert_allclose(SOMQLearner(config, seed=1, **bounds).action_weights[0, [0, 8]], [[-0.5, 0.25], [0.5, 0.75]])
    batched, references = _run_both(config, bounds=bounds, n_steps=100)
    for i, ref in enumerate(references):
        np.testing.assert_array_equal(batched.action_weights[i], ref.action_weights)
        np.testing.assert_array_equal(batched.q[i], ref.q)
