"""Planning over the map's cells (``plan``, ``somarm.learners.planning``) and the grid-placed input map
(``input_placement="grid"``): what the model counts, what solving it gives, that a trial alone plans what it
plans in a batch and a saved learner goes on exactly, the refusals, and that a rare reward's value is known
sooner with it."""

import numpy as np
import pytest
from somq_cases import (
    BOX4,
    batch_and_alone,
    chain_start_values,
    drive_episodes,
    held_bytes,
    saved_between_act_and_learn_goes_on_alike,
    small_config,
)

from somarm.learners.planning import CellModel
from somarm.learners.somq import SOMQConfig, SOMQLearner

PLAN = {"plan": 20, "plan_every": 7}


def _model_of_a_walk() -> CellModel:
    """Units 0 -> 1 -> 2 under action 0 (no pay), then 2 ends paid 1; action 1 tried nowhere."""
    model = CellModel(n_trials=1, n_units=3, n_actions=2)
    one = np.array([True])
    for unit, reward, goes_on in ((0, 0.0, True), (1, 0.0, True), (2, 1.0, False), (0, 0.0, True)):
        model.push(one, np.array([unit]), np.array([0]), np.array([reward]), np.array([goes_on]), np.array([unit + 1]))
    return model


def test_the_model_counts_each_pair_its_pay_and_where_it_led_but_not_past_an_end():
    model = _model_of_a_walk()
    assert model.tries[0, :, 0].tolist() == [2.0, 1.0, 1.0] and model.tries[0, :, 1].sum() == 0.0
    assert model.paid[0, 2, 0] == 1.0 and model.paid[0].sum() == 1.0
    assert model.led[0, 0 * 2 + 0, 1] == 2.0 and model.led[0, 1 * 2 + 0, 2] == 1.0
    assert model.led[0, 2 * 2 + 0].sum() == 0.0  # a termination leads nowhere


def test_solving_the_model_gives_the_discounted_values_and_untried_pairs_keep_q_init():
    q = np.zeros((1, 3, 2))
    _model_of_a_walk().solve(q, gamma=0.9, q_init=5.0, sweeps=10)
    np.testing.assert_allclose(q[0, :, 0], [4.5, 4.5, 1.0])  # every unit has an untried pair worth 5.0 next
    assert (q[0, :, 1] == 5.0).all()
    q = np.zeros((1, 3, 2))
    _model_of_a_walk().solve(q, gamma=0.9, q_init=0.0, sweeps=10)
    np.testing.assert_allclose(q[0, :, 0], [0.81, 0.9, 1.0])


def test_planning_knows_a_rare_rewards_value_at_the_start_sooner():
    planned = chain_start_values({**PLAN, "q_init": 1.0}, 200)
    learned = chain_start_values({"q_init": 1.0}, 200)
    assert (np.abs(planned - 1.0) <= 0.01).all(), planned  # every trial knows gamma^8 within a hundredth
    assert (np.abs(learned - 1.0) > 0.1).all(), learned  # learning each step once: still optimistic everywhere


def test_a_trial_alone_equals_the_same_trial_in_a_batch_with_planning():
    batch, alone = batch_and_alone(small_config((3, 3), True, 0.8).with_changes(PLAN), drive_episodes, 150)
    for name in ("input_weights", "action_weights", "q", "_model_tries", "_model_paid", "_model_led"):
        np.testing.assert_array_equal(getattr(batch, name)[2], getattr(alone, name)[0])
    assert batch._model.tries.sum() == 3 * 150


def test_save_and_load_between_act_and_learn_continue_the_planning_exactly(tmp_path):
    saved_between_act_and_learn_goes_on_alike(small_config((3, 3), True, 0.8).with_changes(PLAN), drive_episodes,
                                              tmp_path, ("q", "_model_tries", "_model_paid", "_model_led"), after=20)


def test_a_learner_file_with_a_negative_count_is_refused_in_one_line(tmp_path):
    learner = SOMQLearner(small_config((3, 3), True, 0.8).with_changes(PLAN), n_trials=1, seed=4, **BOX4)
    drive_episodes(learner, 10)
    learner.save(tmp_path / "l.npz")
    arrays = dict(np.load(tmp_path / "l.npz", allow_pickle=False))
    arrays["_model_tries"][0, 0, 0] = -1.0
    np.savez(tmp_path / "damaged.npz", **arrays)
    with pytest.raises(ValueError, match="is a damaged learner file: _model_tries and _model_led count steps") as caught:
        SOMQLearner.load(tmp_path / "damaged.npz")
    assert "\n" not in str(caught.value)


@pytest.mark.parametrize("changes, message", [
    ({"plan": -1}, "plan must be a whole number >= 0"),
    ({"plan": 2, "plan_every": 0}, "plan_every must be a whole number >= 1"),
    ({"plan": 2, "gamma": 1.0}, "got gamma=1.0"),
    ({"plan": 2, "k_nearest": 3}, "got k_nearest=3"),
    ({"plan": 2, "n_step": 3}, "got n_step=3"),
    ({"plan": 2, "replay": 1}, "got replay=1"),
    ({"plan": 2, "input_groups": "0,1;2,3"}, "got input_groups=0,1;2,3"),
    ({"input_placement": "spiral"}, "input_placement must be one of random, grid"),
])
def test_a_bad_plan_or_placement_is_refused_in_one_line(changes, message):
    with pytest.raises(ValueError, match=message) as caught:
        SOMQConfig(**{"gamma": 0.9, **changes})
    assert "\n" not in str(caught.value)


def test_plan_over_several_maps_is_refused_when_the_maps_are_known():
    with pytest.raises(ValueError, match=r"plan models one input map's cells: it needs one input map, got "
                                         r"input_groups=pairs \(6 maps over 4 dimensions\)"):
        SOMQLearner(SOMQConfig(gamma=0.9, plan=2, input_groups="pairs"), n_trials=1, seed=0, **BOX4)


def test_the_memory_estimate_covers_the_model():
    from somarm import learners

    config = small_config((6, 6), True, 0.8).with_changes(PLAN)
    _, n_bytes = learners.memory_needed("somq", config, n_trials=3, obs_dim=4, action_dim=2)
    learner = SOMQLearner(config, n_trials=3, seed=0, **BOX4)
    model = sum(getattr(learner, "_model_" + name).nbytes for name in CellModel.ARRAYS)
    assert model >= 3 * 36 * 7 * 36 * 4 and held_bytes(learner) <= n_bytes + 64 * (3 + 4 + 2)


def test_a_grid_placed_map_puts_each_unit_in_the_middle_of_its_cell():
    box = dict(observation_low=[-1.0, 0.0], observation_high=[1.0, 10.0], action_low=[-1.0], action_high=[1.0])
    learner = SOMQLearner(SOMQConfig(input_shape=(2, 5), action_shape=(3,), input_placement="grid"), n_trials=2, seed=3,
                          **box)
    units = learner.input_weights[0, :10]
    np.testing.assert_allclose(units[:, 0], np.repeat([-0.5, 0.5], 5))
    np.testing.assert_allclose(units[:, 1], np.tile([1.0, 3.0, 5.0, 7.0, 9.0], 2))
    np.testing.assert_array_equal(learner.input_weights[1], learner.input_weights[0])  # no draw: every trial alike


def test_a_grid_placed_map_needs_a_grid_axis_per_dimension():
    with pytest.raises(ValueError, match=r"input_placement=grid needs a map with one grid axis per dimension it sees: "
                                         r"input_shape=3x3 has 2, the map sees 4"):
        SOMQLearner(SOMQConfig(input_shape=(3, 3), input_placement="grid"), n_trials=1, seed=0, **BOX4)


def test_the_sweeps_over_the_transitions_seen_equal_value_iteration_over_the_whole_table():
    rng = np.random.default_rng(5)
    model = CellModel(n_trials=2, n_units=12, n_actions=3)
    for _ in range(400):
        model.push(np.array([True, rng.random() < 0.5]), rng.integers(0, 12, 2), rng.integers(0, 3, 2), rng.random(2),
                   rng.random(2) < 0.9, rng.integers(0, 12, 2))
    q = rng.random((2, 12, 3))
    expected = q.copy()
    for trial in range(2):  # plain value iteration with the dense table of chances
        tried = model.tries[trial] > 0
        tries = np.maximum(model.tries[trial], 1.0)
        chances = model.led[trial].astype(np.float64) / tries.reshape(-1, 1)
        values = np.where(tried, expected[trial], 2.0)
        for _ in range(15):
            values = np.where(tried, model.paid[trial] / tries + 0.9 * (chances @ values.max(axis=1)).reshape(12, 3), 2.0)
        expected[trial] = values
    model.solve(q, gamma=0.9, q_init=2.0, sweeps=15)
    np.testing.assert_allclose(q, expected, rtol=1e-12)
