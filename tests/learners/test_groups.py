import numpy as np
import pytest
from somq_cases import BOX4, batch_and_alone, saved_between_act_and_learn_goes_on_alike, small_config

from somarm.learners import grouping, groups
from somarm.learners.schedules import InverseDecay, Schedule
from somarm.learners.somq import SOMQConfig, SOMQLearner


def _drive(learner, steps, seed=5, gamma_next=True):
    """Random observations and rewards (one stream for every trial count), acting and learning."""
    rng = np.random.default_rng(seed)
    low, high = learner.observation_low, learner.observation_high
    for _ in range(steps):
        x = low + (high - low) * rng.random((1, low.size))
        x = np.repeat(x, learner.n_trials, axis=0)
        actions = learner.act(x)
        r = -np.abs(actions).sum(axis=1) + x[:, 0]
        nxt = np.repeat(low + (high - low) * rng.random((1, low.size)), learner.n_trials, axis=0)
        learner.learn(r, nxt, np.zeros(learner.n_trials, dtype=bool) if gamma_next else True)


@pytest.mark.parametrize("neighbourhood_q", [True, False])
@pytest.mark.parametrize("gamma", [0.0, 0.7])
def test_one_group_of_every_dimension_in_order_is_the_papers_kernel_bit_for_bit(neighbourhood_q, gamma):
    paper = small_config((3, 4), neighbourhood_q, gamma)
    grouped = paper.with_changes({"input_groups": "0,1,2,3"})
    assert grouped.grouped and not paper.grouped
    a, b = SOMQLearner(paper, n_trials=2, seed=3, **BOX4), SOMQLearner(grouped, n_trials=2, seed=3, **BOX4)
    np.testing.assert_array_equal(a.input_weights, b.input_weights)
    _drive(a, 120)
    _drive(b, 120)
    for name in ("input_weights", "action_weights", "q"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name))
    x = np.random.default_rng(0).random((2, 7, 4))
    np.testing.assert_array_equal(a.predict(x), b.predict(x))
    np.testing.assert_array_equal(a.greedy_units(x)[1], b.greedy_units(x)[1])


@pytest.mark.parametrize("changes", [{"input_groups": "pairs"}, {"k_nearest": 3},
                                     {"input_groups": "0,2;1,3", "k_nearest": 2, "response": "interpolated"},
                                     {"input_groups": "singles", "k_nearest": 2, "local_linear": True},
                                     {"input_groups": "pairs", "local_linear": True, "neighbourhood_q": False},
                                     {"input_groups": "pairs", "action_factored": True, "k_nearest": 2},
                                     {"input_groups": "singles", "action_factored": True, "local_linear": True,
                                      "response": "interpolated", "neighbourhood_q": False},
                                     {"input_groups": "pairs", "k_nearest": 2, "action_gap": 0.5},
                                     {"action_gap": 0.8, "action_factored": True, "local_linear": True},
                                     {"input_groups": "pairs", "local_linear": True, "shared_slopes": True},
                                     {"input_groups": "singles", "local_linear": True, "shared_slopes": True,
                                      "neighbourhood_q": False, "k_nearest": 2},
                                     {"input_groups": "pairs", "local_linear": True, "shared_slopes": True,
                                      "action_factored": True, "k_nearest": 2},
                                     {"input_groups": "pairs", "local_linear": True, "shared_slopes": True,
                                      "action_slopes": True, "k_nearest": 2},
                                     {"input_groups": "singles", "local_linear": True, "shared_slopes": True,
                                      "action_slopes": True, "neighbourhood_q": False, "response": "interpolated"}])
def test_a_trial_alone_equals_the_same_trial_in_a_batch(changes):
    batch, alone = batch_and_alone(small_config((3, 3), True, 0.5).with_changes(changes), _drive, 80)
    for name in ("input_weights", "action_weights", "q", "slopes"):
        np.testing.assert_array_equal(getattr(batch, name)[2], getattr(alone, name)[0])
    x = np.random.default_rng(1).random((1, 5, 4)) * [1.0, 2.0, 2.0, 4.0] - [0.0, 1.0, 0.0, 2.0]
    np.testing.assert_array_equal(batch.predict(np.repeat(x, 3, axis=0))[2], alone.predict(x)[0])


def test_groupings_name_the_dimensions_each_map_sees():
    assert grouping.parse_groups("all", 3) == [[0, 1, 2]]
    assert grouping.parse_groups("pairs", 3) == [[0, 1], [0, 2], [1, 2]]
    assert grouping.parse_groups("triples", 4) == [[0, 1, 2], [0, 1, 3], [0, 2, 3], [1, 2, 3]]
    assert grouping.parse_groups("singles", 2) == [[0], [1]]
    assert grouping.parse_groups("chunks:2", 5) == [[0, 1], [2, 3], [4]]
    assert grouping.parse_groups("0,3; 1", 4) == [[0, 3], [1]]
    np.testing.assert_array_equal(grouping.group_table([[0, 3], [1]]), [[0, 3], [1, -1]])


@pytest.mark.parametrize("text, match", [("two", "input_groups must be"), ("chunks:0", "input_groups must be"),
                                         ("0,0", "repeated"), ("0,-1", "input_groups must be")])
def test_a_bad_grouping_is_refused_in_one_line(text, match):
    with pytest.raises(ValueError, match=match):
        SOMQConfig(input_groups=text)


def test_a_dimension_the_observation_lacks_is_named():
    with pytest.raises(ValueError, match=r"dimension\(s\) 7, but the observation has 4"):
        SOMQLearner(SOMQConfig(input_shape=(3,), action_shape=(3,), input_groups="0,7"), **BOX4)
    with pytest.raises(ValueError, match="k_nearest must be"):
        SOMQConfig(k_nearest=0)


def test_k_nearest_weights_are_tapered_and_sum_to_one():
    config = SOMQConfig(input_shape=(4,), action_shape=(2,), k_nearest=2, lambda_s=0.0)
    learner = SOMQLearner(config, observation_low=[0.0], observation_high=[3.0], action_low=[0.0], action_high=[1.0])
    learner.input_weights[0, :, 0] = [0.0, 1.0, 2.0, 3.0]
    learner.act([[1.25]])  # nearest 1 (0.25), 2 (0.75), then 0 (1.25): 1/0.25 - 1/1.25 = 3.2, 1/0.75 - 0.8
    expected = np.array([3.2, 1 / 0.75 - 0.8])
    np.testing.assert_array_equal(learner._group_units[0, 0], [1, 2])
    np.testing.assert_allclose(learner._phi[0, 0], expected / expected.sum())
    learner.learn([0.0])
    learner.act([[2.0]])  # on a unit: that unit alone
    np.testing.assert_array_equal(learner._phi[0, 0], [1.0, 0.0])


def test_tables_start_at_a_share_of_q_init_so_the_sum_starts_at_it():
    learner = SOMQLearner(SOMQConfig(input_shape=(3,), action_shape=(3,), input_groups="singles", q_init=8.0), **BOX4)
    assert learner.q.shape == (1, 12, 3) and np.all(learner.q == 2.0)
    assert learner.input_weights.shape == (1, 12, 1)


def test_interpolated_response_moves_to_the_top_of_the_parabola():
    config = SOMQConfig(input_shape=(1,), action_shape=(5,), input_groups="singles", response="interpolated",
                        action_init="grid", p=0.0, epsilon=0.0)
    learner = SOMQLearner(config, observation_low=[0.0], observation_high=[1.0], action_low=[-1.0], action_high=[1.0])
    learner.q[0, 0] = [0.0, 1.0, 2.0, 1.5, 0.0]  # unit 2 (at 0); parabola through 1, 2, 1.5 tops at +0.1 steps
    np.testing.assert_allclose(learner.predict([[0.3]]), [[0.5 * (1.0 - 1.5) / (1.0 - 4.0 + 1.5) * 0.5]])
    plain = SOMQLearner(config.with_changes({"response": "winner"}), observation_low=[0.0], observation_high=[1.0],
                 action_low=[-1.0], action_high=[1.0])
    plain.q[...] = learner.q
    np.testing.assert_array_equal(plain.predict([[0.3]]), [[0.0]])


def test_save_and_load_continue_exactly(tmp_path):
    config = small_config((3,), True, 0.5).with_changes({"input_groups": "pairs", "k_nearest": 2})
    saved_between_act_and_learn_goes_on_alike(config, _drive, tmp_path, ("input_weights", "action_weights", "q"))


def _planted_sum(input_groups, steps, seed):
    """Two independent one-dimensional problems whose rewards add: action dimension i is best at
    +0.5 where observation i > 0.5 and at -0.5 below, each a 2-unit grid; returns the greedy
    policy's share of right torques over fresh observations."""
    config = SOMQConfig(
        input_shape=(2,), action_shape=(2, 2), action_init="grid", grid_span=0.5, alpha=Schedule(0.5),
        lambda_s=Schedule(0.0), lambda_a=Schedule(0.0), n_s=Schedule(0.0), n_a=Schedule(0.0),
        p=Schedule(1.0, InverseDecay(500.0), 0.1), epsilon=Schedule(0.0), input_groups=input_groups)
    learner = SOMQLearner(config, n_trials=4, seed=seed, observation_low=[0.0, 0.0], observation_high=[1.0, 1.0],
                   action_low=[-1.0, -1.0], action_high=[1.0, 1.0])
    learner.input_weights[:] = np.array([[0.25], [0.75], [0.25], [0.75]]) if input_groups == "singles" else (
        np.array([[0.25, 0.25], [0.75, 0.75]]))
    rng = np.random.default_rng(seed)
    for _ in range(steps):
        x = rng.random((4, 2))
        a = learner.act(x)
        right = np.where(x > 0.5, 0.5, -0.5)
        learner.learn(-np.abs(a - right).sum(axis=1))
    x = rng.random((4, 500, 2))
    return float(np.mean(np.sign(learner.predict(x)) == np.where(x > 0.5, 1.0, -1.0)))


def test_maps_whose_values_add_solve_two_independent_problems_one_map_of_two_units_cannot():
    # The two problems' quadrants need 4 states; one map of 2 units over both dimensions holds 2, two maps
    # of 2 units (one per dimension) hold every combination through their sum.
    grouped = _planted_sum("singles", 3000, 1)
    single = _planted_sum("all", 3000, 1)
    assert grouped >= 0.99, grouped
    assert single <= 0.8, single


def test_a_growing_map_starts_at_two_by_two_and_grows_to_its_bound_a_row_or_column_at_a_time():
    config = small_config((3, 4), True, 0.0).with_changes({"grow_every": 10, "input_groups": "0,1;2,3"})
    learner = SOMQLearner(config, n_trials=2, seed=1, **BOX4)
    np.testing.assert_array_equal(learner._shapes, np.full((2, 2, 2), 2))
    _drive(learner, 10)
    assert np.all(learner._shapes.prod(axis=2) == 6)  # one row or one column more
    _drive(learner, 60)
    np.testing.assert_array_equal(learner._shapes, np.tile([3, 4], (2, 2, 1)))  # full: 12 units, no more


def test_growth_inserts_the_mean_of_the_two_units_beside_the_largest_error():
    from somarm.learners.growing import grow

    weights = np.zeros((6, 1))
    weights[:4, 0] = [0.0, 1.0, 0.0, 5.0]  # 2x2: unit 3 is far from unit 2 (beside it) and from unit 1 (above)
    q = np.zeros((6, 2))
    q[:4, 0] = [1.0, 2.0, 3.0, 4.0]
    errors = np.array([0.0, 0.0, 0.0, 9.0, 0.0, 0.0])
    shape = np.array([2, 2])
    grow(weights, q, errors, shape, 2, 3)  # f = unit 2 (distance 25 against 16): a new column between them
    np.testing.assert_array_equal(shape, [2, 3])
    np.testing.assert_array_equal(weights[:, 0], [0.0, 0.5, 1.0, 0.0, 2.5, 5.0])
    np.testing.assert_array_equal(q[:, 0], [1.0, 1.5, 2.0, 3.0, 3.5, 4.0])
    assert not errors.any()
    grow(weights, q, errors, shape, 2, 3)  # full
    np.testing.assert_array_equal(shape, [2, 3])


@pytest.mark.parametrize("grow_every", [0, 7])
def test_a_growing_trial_alone_equals_the_same_trial_in_a_batch(grow_every):
    config = small_config((3, 3), True, 0.5).with_changes({"grow_every": grow_every, "k_nearest": 2})
    batch = SOMQLearner(config, n_trials=3, seed=2, **BOX4)
    alone = SOMQLearner(config, n_trials=1, seed=2, trial_ids=[1], **BOX4)
    _drive(batch, 60)
    _drive(alone, 60)
    for name in ("input_weights", "action_weights", "q", "_shapes"):
        np.testing.assert_array_equal(getattr(batch, name)[1], getattr(alone, name)[0])


def test_the_memory_check_before_a_task_is_built_takes_index_lists_beyond_its_lower_bound():
    # A run checks memory with obs_dim=1 before its task exists; index lists name more dimensions.
    import dataclasses

    from somarm.learners import presets, somq

    config = dataclasses.replace(presets.get("invertedpendulum"), input_groups="1,3;0,2")
    what, n_bytes = somq.SOMQLearner.memory_needed(config, n_trials=2, obs_dim=1, action_dim=1)
    assert "2 input map(s)" in what and n_bytes > 0


def test_grouped_maps_say_they_have_no_one_input_map_to_draw_and_a_run_folder_is_written(tmp_path):
    from somarm import run
    from somarm.run import RunConfig

    learner = SOMQLearner(SOMQConfig(input_shape=(3,), action_shape=(3,), input_groups="pairs"), **BOX4)
    assert not learner.has_maps and SOMQLearner(SOMQConfig(), **BOX4).has_maps
    result = run.train(RunConfig(task="reach2", n_trials=1, n_steps=50, block=25, seed=1,
                                 overrides={"input_groups": "singles", "input_shape": (3, 3)}), progress=False)
    run.write(result, tmp_path / "run")  # with the figures
    assert (tmp_path / "run" / "learning_curve.png").exists()


def _planted_unseen(local_linear, steps, seed):
    """One map over observation 0 alone; action 0 is best at +0.5 where observation 1 (which no map sees) is
    above its middle and at -0.5 below, a 2-unit grid. Returns the greedy policy's share of right torques."""
    config = SOMQConfig(
        input_shape=(3,), action_shape=(2,), action_init="grid", grid_span=0.5, alpha=Schedule(0.5),
        lambda_s=Schedule(0.0), lambda_a=Schedule(0.0), n_s=Schedule(0.0), n_a=Schedule(0.0),
        p=Schedule(1.0, InverseDecay(500.0), 0.1), epsilon=Schedule(0.0), input_groups="0", local_linear=local_linear)
    learner = SOMQLearner(config, n_trials=2, seed=seed, observation_low=[0.0, -1.0], observation_high=[1.0, 1.0],
                          action_low=[-1.0], action_high=[1.0])
    rng = np.random.default_rng(seed)
    for _ in range(steps):
        x = rng.random((2, 2)) * [1.0, 2.0] - [0.0, 1.0]
        a = learner.act(x)
        learner.learn(-np.abs(a[:, 0] - np.where(x[:, 1] > 0.0, 0.5, -0.5)))
    x = rng.random((2, 500, 2)) * [1.0, 2.0] - [0.0, 1.0]
    return float(np.mean(np.sign(learner.predict(x)[..., 0]) == np.where(x[..., 1] > 0.0, 1.0, -1.0)))


def test_local_linear_units_answer_to_a_dimension_their_map_does_not_see():
    # The best torque's sign follows observation 1; the map sees only observation 0. Constant units hold one
    # torque per unit (about half right); local linear units' slopes along observation 1 turn the choice.
    linear = _planted_unseen(True, 3000, 3)
    constant = _planted_unseen(False, 3000, 3)
    assert linear >= 0.9, linear
    assert constant <= 0.7, constant


def test_local_linear_answers_are_the_constant_plus_the_slopes_along_the_place_round_the_unit():
    config = SOMQConfig(input_shape=(1,), action_shape=(2,), input_groups="0", local_linear=True, p=0.0,
                        epsilon=0.0, action_init="grid")
    learner = SOMQLearner(config, observation_low=[0.0, -1.0], observation_high=[1.0, 1.0], action_low=[-1.0],
                          action_high=[1.0])
    learner.input_weights[0, 0, 0] = 0.25
    learner.q[0, 0] = [0.0, 0.1]
    learner.slopes[0, 0, 1, 1] = 1.0  # action unit 1 gains along observation 1, over its span of 2
    # At x = (0.75, -1): z = (0.5, -0.5): unit 1 answers 0.1 - 0.5 < 0 = unit 0; at x1 = 1 it answers 0.6.
    np.testing.assert_array_equal(learner.predict([[0.75, -1.0]]), [[-1.0]])
    np.testing.assert_array_equal(learner.predict([[0.75, 1.0]]), [[1.0]])


def test_local_linear_is_refused_with_growing_maps_in_one_line():
    with pytest.raises(ValueError, match="local_linear applies to maps of a fixed size"):
        SOMQConfig(local_linear=True, grow_every=10)


def _planted_separable(factored, steps, seed):
    """One input unit, a 5x5 grid of actions over [-1, 1]^2, each step a random unit rewarded
    ``-(a_0 - 0.5)^2 - (a_1 + 0.5)^2`` (the two action dimensions' parts add); returns the share of 40
    trials whose greedy unit is the best one, (0.5, -0.5)."""
    config = SOMQConfig(
        input_shape=(1,), action_shape=(5, 5), action_init="grid", alpha=Schedule(0.5), lambda_s=Schedule(0.0),
        lambda_a=Schedule(0.0), n_s=Schedule(0.0), n_a=Schedule(0.0), p=Schedule(1.0), epsilon=Schedule(0.0),
        q_init=-10.0, action_factored=factored, input_groups="0")
    learner = SOMQLearner(config, n_trials=40, seed=seed, observation_low=[0.0], observation_high=[1.0],
                          action_low=[-1.0, -1.0], action_high=[1.0, 1.0])
    x = np.full((40, 1), 0.5)
    for _ in range(steps):
        a = learner.act(x)
        learner.learn(-((a[:, 0] - 0.5) ** 2) - (a[:, 1] + 0.5) ** 2)
    return float(np.mean(np.all(learner.predict(x) == [0.5, -0.5], axis=1)))


def test_a_factored_table_finds_the_best_of_a_separable_reward_from_fewer_tries():
    # 160 random tries of 25 action units at a learning rate of 0.5: the full table's values of the best unit
    # and its neighbours have had a few tries each, not yet enough to tell them apart; the factored one
    # learns each axis's 5 places from every try.
    factored = _planted_separable(True, 160, 2)
    full = _planted_separable(False, 160, 2)
    assert factored >= 0.9, factored
    assert full <= 0.75, full


def test_a_factored_table_holds_a_column_per_place_of_each_axis_and_answers_their_sum():
    config = SOMQConfig(input_shape=(2,), action_shape=(2, 3), action_init="grid", action_factored=True, p=0.0,
                        epsilon=0.0, input_groups="0", q_init=4.0)
    learner = SOMQLearner(config, observation_low=[0.0], observation_high=[1.0], action_low=[-1.0, -1.0],
                          action_high=[1.0, 1.0])
    assert learner.q.shape == (1, 2, 5) and np.all(learner.q == 2.0)  # 2 + 3 columns, q_init / 2 axes
    learner.input_weights[0, :, 0] = [0.0, 1.0]
    learner.q[0, 0] = [0.0, 1.0, 0.0, 0.0, 0.5]  # rows: place 1 best; cols: place 2 best
    np.testing.assert_array_equal(learner.predict([[0.1]]), [[1.0, 1.0]])
    assert learner.greedy_units(np.array([[0.1]]))[1][0] == 1 * 3 + 2


def _bandit_values(gap, steps=4000):
    """One input unit, 3 action units on a line, each step a random unit rewarded 0, 1 or 0.5 (no next
    state), a constant learning rate of 0.05: the learned Q of the three units."""
    config = SOMQConfig(
        input_shape=(1,), action_shape=(3,), action_init="grid", alpha=Schedule(0.05), lambda_s=Schedule(0.0),
        lambda_a=Schedule(0.0), n_s=Schedule(0.0), n_a=Schedule(0.0), p=Schedule(1.0), epsilon=Schedule(0.0),
        neighbourhood_q=False, input_groups="0", action_gap=gap)
    learner = SOMQLearner(config, seed=4, observation_low=[0.0], observation_high=[1.0], action_low=[-1.0],
                          action_high=[1.0])
    rewards = {-1.0: 0.0, 0.0: 1.0, 1.0: 0.5}
    for _ in range(steps):
        action = learner.act([[0.5]])
        learner.learn([rewards[float(action[0, 0])]])
    return learner.q[0, 0]


@pytest.mark.parametrize("gap", [0.0, 0.5, 0.75])
def test_advantage_learning_keeps_the_best_value_and_widens_the_others_gaps_by_one_over_one_less_the_gap(gap):
    # The fixed point of Q(a) <- r(a) - gap (max_b Q(b) - Q(a)) is Q(a) = r* - (r* - r(a)) / (1 - gap).
    expected = 1.0 - (1.0 - np.array([0.0, 1.0, 0.5])) / (1.0 - gap)
    np.testing.assert_allclose(_bandit_values(gap), expected, atol=0.06)


@pytest.mark.parametrize("gap", [-0.1, 1.0, float("nan"), "wide"])
def test_an_action_gap_outside_zero_to_one_is_refused_in_one_line(gap):
    with pytest.raises(ValueError, match="action_gap must be"):
        SOMQConfig(action_gap=gap)


def test_an_action_gap_runs_the_grouped_kernels_and_zero_is_the_papers_path():
    assert SOMQConfig(action_gap=0.5).grouped and not SOMQConfig(action_gap=0.0).grouped


def test_shared_slopes_hold_one_slope_vector_per_unit_and_answer_it_for_every_action():
    config = small_config((3, 3), True, 0.5).with_changes({"input_groups": "pairs", "local_linear": True,
                                                           "shared_slopes": True, "k_nearest": 2})
    learner = SOMQLearner(config, n_trials=2, seed=9, **BOX4)
    assert learner.slopes.shape == (2, 6 * 9, 1, 4)
    _drive(learner, 60)
    assert np.any(learner.slopes != 0.0)
    # A unit's answer is its constant plus the one slope term: raising a unit's slope along a dimension
    # the maps do not see shifts every action's summed value alike, so the greedy action does not change.
    x = np.random.default_rng(2).random((2, 5, 4)) * [1.0, 2.0, 2.0, 4.0] - [0.0, 1.0, 0.0, 2.0]
    before = learner.greedy_units(x)[1]
    learner.slopes[..., 0, :] += 3.0
    np.testing.assert_array_equal(learner.greedy_units(x)[1], before)


def test_shared_slopes_learn_a_value_that_varies_within_a_unit_from_every_action_tried():
    # One unit over dimension 0 only; the reward grows with dimension 1, which no map sees, and not with
    # the action: shared slopes learn that from every step, and the summed Q then follows dimension 1.
    config = SOMQConfig(input_shape=(1,), action_shape=(3,), action_init="grid", alpha=Schedule(0.2),
                        lambda_s=Schedule(0.0), lambda_a=Schedule(0.0), n_s=Schedule(0.0), n_a=Schedule(0.0),
                        p=Schedule(1.0), epsilon=Schedule(0.0), neighbourhood_q=False, input_groups="0",
                        local_linear=True, shared_slopes=True)
    learner = SOMQLearner(config, seed=1, observation_low=[0.0, 0.0], observation_high=[1.0, 1.0],
                          action_low=[-1.0], action_high=[1.0])
    rng = np.random.default_rng(0)
    for _ in range(3000):
        x = rng.random((1, 2))
        learner.act(x)
        learner.learn(2.0 * x[:, 1])
    slope = learner.slopes[0, 0, 0, 1]
    assert abs(slope - 2.0) < 0.2, slope


def test_a_factored_table_with_shared_slopes_learns_each_axis_best_place_and_the_slope_once():
    # Reward 2 x_1 (a dimension no map sees) less each torque's squared distance from its own best place
    # (0 on the first axis, 1 on the second): one slope vector of 2 for the sum, and each axis' columns
    # ranking its places by their own penalty alone.
    config = SOMQConfig(input_shape=(1,), action_shape=(3, 3), action_init="grid", alpha=Schedule(0.2),
                        lambda_s=Schedule(0.0), lambda_a=Schedule(0.0), n_s=Schedule(0.0), n_a=Schedule(0.0),
                        p=Schedule(1.0), epsilon=Schedule(0.0), neighbourhood_q=False, input_groups="0",
                        local_linear=True, shared_slopes=True, action_factored=True)
    learner = SOMQLearner(config, seed=1, observation_low=[0.0, 0.0], observation_high=[1.0, 1.0],
                          action_low=[-1.0, -1.0], action_high=[1.0, 1.0])
    assert learner.slopes.shape == (1, 1, 1, 2)
    rng = np.random.default_rng(0)
    for _ in range(4000):
        x = rng.random((1, 2))
        actions = learner.act(x)
        learner.learn(2.0 * x[:, 1] - actions[:, 0] ** 2 - (actions[:, 1] - 1.0) ** 2)
    assert abs(learner.slopes[0, 0, 0, 1] - 2.0) < 0.1, learner.slopes[0, 0, 0]
    rows, cols = learner.q[0, 0, :3], learner.q[0, 0, 3:]
    np.testing.assert_allclose(rows - rows[1], [-1.0, 0.0, -1.0], atol=0.1)
    np.testing.assert_allclose(cols - cols[2], [-4.0, -1.0, 0.0], atol=0.1)
    np.testing.assert_array_equal(learner.predict(np.array([[0.5, 0.5]])), [[0.0, 1.0]])


def test_shared_slopes_without_local_linear_are_refused_in_one_line():
    with pytest.raises(ValueError, match="^shared_slopes needs local_linear=true, got local_linear=false$"):
        SOMQConfig(shared_slopes=True)


def test_action_slopes_learn_a_best_action_that_changes_within_one_unit():
    # One unit over dimension 0 only; the reward 2 a (x_1 - 1/2) favours a = +1 above x_1 = 1/2 and a = -1
    # below it, in a dimension no map sees. Its value is linear in the action's place times x_1: the action
    # slope along x_1 learns 2, and the greedy action follows x_1 where one value per action could not.
    config = SOMQConfig(input_shape=(1,), action_shape=(3,), action_init="grid", alpha=Schedule(0.2),
                        lambda_s=Schedule(0.0), lambda_a=Schedule(0.0), n_s=Schedule(0.0), n_a=Schedule(0.0),
                        p=Schedule(1.0), epsilon=Schedule(0.0), neighbourhood_q=False, input_groups="0",
                        local_linear=True, shared_slopes=True, action_slopes=True)
    box = dict(observation_low=[0.0, 0.0], observation_high=[1.0, 1.0], action_low=[-1.0], action_high=[1.0])
    learner = SOMQLearner(config, seed=1, **box)
    plain = SOMQLearner(config.with_changes({"action_slopes": False}), seed=1, **box)
    assert learner.slopes.shape == (1, 1, 2, 2)
    rng = np.random.default_rng(0)
    for _ in range(4000):
        x = rng.random((1, 2))
        for one in (learner, plain):
            actions = one.act(x)
            one.learn(2.0 * actions[:, 0] * (x[:, 1] - 0.5))
    assert abs(learner.slopes[0, 0, 1, 1] - 2.0) < 0.1, learner.slopes[0, 0]
    np.testing.assert_allclose(learner.slopes[0, 0, 0], 0.0, atol=0.1)
    x = np.array([[[0.5, 0.1], [0.5, 0.4], [0.5, 0.6], [0.5, 0.9]]])
    np.testing.assert_array_equal(learner.predict(x)[0, :, 0], [-1.0, -1.0, 1.0, 1.0])
    assert len(set(plain.predict(x)[0, :, 0])) == 1


@pytest.mark.parametrize("changes, message", [
    ({"local_linear": True, "action_slopes": True},
     "^action_slopes needs shared_slopes=true, got shared_slopes=false$"),
    ({"local_linear": True, "shared_slopes": True, "action_slopes": True, "action_factored": True},
     "^action_slopes needs a table column per action unit: it needs action_factored=false, got action_factored=true$"),
])
def test_action_slopes_without_shared_slopes_or_with_a_factored_table_are_refused_in_one_line(changes, message):
    with pytest.raises(ValueError, match=message):
        SOMQConfig(**changes)


@pytest.mark.parametrize("rows, places_j", [(9, 0), (1, 0), (3, 2)])
def test_the_summed_local_linear_answer_is_each_units_constant_plus_its_slope_term(rows, places_j):
    # One slope vector per column (9), one shared by every column (1: its term computed once a unit), and
    # shared slopes with one per action axis (3 with 2 places): the kernel's sum against the formula.
    rng = np.random.default_rng(4)
    n_groups, k, units_per_map, obs_dim, n_actions = 3, 2, 4, 5, 9
    group_dims = np.array([[0, 1], [2, 3], [4, -1]])
    q = rng.normal(size=(n_groups * units_per_map, n_actions))
    slopes = rng.normal(size=(n_groups * units_per_map, rows, obs_dim))
    places = rng.uniform(-1.0, 1.0, size=(n_actions, places_j))
    units = np.array([[g * units_per_map + i for i in (1, 3)] for g in range(n_groups)])
    phi = rng.random((n_groups, k))
    x, mid, span = rng.normal(size=obs_dim), rng.normal(size=obs_dim), rng.uniform(0.5, 2.0, size=obs_dim)
    weights = rng.normal(size=(n_groups * units_per_map, 2))
    values = np.empty(n_actions)
    groups._summed_linear(q, slopes, places, units, phi, x, weights, group_dims, mid, span, np.empty(obs_dim), 0.5,
                          values)
    expected = np.zeros(n_actions)
    for g in range(n_groups):
        for i in range(k):
            u = units[g, i]
            z = (x - mid) / span
            for j, d in enumerate(group_dims[g]):
                if d >= 0:
                    z[d] = (x[d] - weights[u, j]) / span[d]
            for a in range(n_actions):
                slope = slopes[u, a] if rows == n_actions else slopes[u, 0] + places[a] @ slopes[u, 1:1 + places_j]
                expected[a] += phi[g, i] * (q[u, a] + 0.5 * slope @ z)
    np.testing.assert_allclose(values, expected, rtol=1e-12, atol=1e-12)
