import json

import numpy as np
import pytest

from somarm.learners.schedules import ExponentialDecay, InverseDecay, Schedule
from somarm.learners.somq import SOMQConfig, SOMQLearner, grid_actions
from somarm.protocols import Learner

BOX1 = dict(observation_low=[0.0], observation_high=[3.0], action_low=[0.0, 0.0], action_high=[1.0, 1.0])
BOX2 = dict(observation_low=[0.0, 0.0], observation_high=[1.0, 1.0], action_low=[-1.0, -1.0],
            action_high=[1.0, 1.0])


def _planted(neighbourhood_q=True):
    """Three input units at 0, 1, 2; three action units on the diagonal; constant rates 0.5, widths 1."""
    config = SOMQConfig(input_shape=(3,), action_shape=(3,), alpha=0.5, lambda_s=0.5, lambda_a=0.5, n_s=1.0,
                        n_a=1.0, p=0.0, epsilon=0.0, neighbourhood_q=neighbourhood_q)
    learner = SOMQLearner(config, **BOX1)
    learner.input_weights[0] = [[0.0], [1.0], [2.0]]
    learner.action_weights[0] = [[0.0, 0.0], [0.5, 0.5], [1.0, 1.0]]
    learner.q[0] = -1.0
    learner.q[0, 1, 1] = -0.5
    return learner


def test_one_update_with_planted_weights_exact_arrays():
    learner = _planted()
    action = learner.act([[1.25]])  # winner s_1; best Q in row 1 is a_1; epsilon 0 -> the unit itself
    np.testing.assert_array_equal(action, [[0.5, 0.5]])
    learner.learn([0.5])  # 0.5 > Q(s_1, a_1) = -0.5: the action map moves (towards where it already is)
    # Action map: rates lambda_A * psi_A = [0.25, 0.5, 0.25] towards (0.5, 0.5).
    np.testing.assert_array_equal(learner.action_weights[0], [[0.125, 0.125], [0.5, 0.5], [0.875, 0.875]])
    # Q: alpha * psi_S[m] * psi_A[n] = 0.5 * [0.5, 1, 0.5] x [0.5, 1, 0.5], towards r = 0.5.
    np.testing.assert_array_equal(
        learner.q[0],
        [[-0.8125, -0.625, -0.8125], [-0.625, 0.0, -0.625], [-0.8125, -0.625, -0.8125]],
    )
    # Input map: rates [0.25, 0.5, 0.25] towards 1.25.
    np.testing.assert_array_equal(learner.input_weights[0], [[0.3125], [1.125], [1.8125]])
    assert learner.t == 1


def test_no_improvement_leaves_action_map_and_no_nl_moves_only_the_winning_pair():
    learner = _planted(neighbourhood_q=False)
    before = learner.action_weights.copy()
    learner.act([[1.25]])
    learner.learn([-2.0])  # -2 < Q(s_1, a_1) = -0.5: no action-map learning
    np.testing.assert_array_equal(learner.action_weights, before)
    expected = np.full((3, 3), -1.0)
    expected[1, 1] = -0.5 + 0.5 * (-2.0 + 0.5)
    np.testing.assert_array_equal(learner.q[0], expected)


def test_delayed_reward_bootstraps_from_next_winner_and_terminal_does_not():
    learner = SOMQLearner(
        SOMQConfig(input_shape=(3,), action_shape=(3,), alpha=1.0, lambda_s=0.0, lambda_a=0.0, n_s=0.0,
                   n_a=0.0, p=0.0, epsilon=0.0, gamma=0.5, neighbourhood_q=False), **BOX1)
    learner.input_weights[0] = [[0.0], [1.0], [2.0]]
    learner.q[0] = [[0.0, 0.0, 0.0], [-1.0, -1.0, -1.0], [4.0, 2.0, 0.0]]
    learner.act([[0.9]])  # s_1; all Q tied at -1
    k = learner._units[0]
    learner.learn([1.0], [[2.2]], False)  # s'_j = s_2, max Q = 4 -> target 1 + 0.5 * 4 = 3 (alpha 1)
    assert learner.q[0, 1, k] == 3.0
    learner.act([[0.9]])
    k = learner._units[0]
    learner.learn([1.0], [[2.2]], np.array([True]))
    assert learner.q[0, 1, k] == 1.0
    learner.act([[0.9]])
    with pytest.raises(ValueError, match="next_observations"):
        learner.learn([1.0], None, False)


def test_exploration_picks_random_units_and_noise_stays_in_bounds():
    config = SOMQConfig(input_shape=(2,), action_shape=(6,), p=1.0, epsilon=5.0)
    learner = SOMQLearner(config, n_trials=50, seed=2, **BOX2)
    seen, actions = set(), []
    for _ in range(20):
        actions.append(learner.act(np.full((50, 2), 0.5)))
        seen |= set(learner._units.tolist())
        learner.learn(np.zeros(50))
    actions = np.concatenate(actions)
    assert seen == set(range(6))
    assert actions.min() == -1.0 and actions.max() == 1.0  # big noise: clipped to the box, never beyond


def _greedy_error_single_state(steps):
    config = SOMQConfig(input_shape=(1,), action_shape=(5,)).with_overrides(
        {"decay": "inv:200", "n_a": "2", "epsilon": "0.2", "p": "0.5"})
    learner = SOMQLearner(config, n_trials=10, seed=3, observation_low=[0], observation_high=[1],
                   action_low=[0, 0], action_high=[1, 1])
    best, x = np.array([0.3, 0.7]), np.zeros((10, 1))
    before = np.linalg.norm(learner.predict(x) - best, axis=1)
    for _ in range(steps):
        learner.learn(-np.linalg.norm(learner.act(x) - best, axis=1))
    return before, np.linalg.norm(learner.predict(x) - best, axis=1)


def test_known_optimum_single_state():
    before, after = _greedy_error_single_state(1000)
    assert before.mean() > 0.2  # random initial action units
    assert after.mean() < 0.02 and after.max() < 0.03  # measured: mean 0.005, max 0.007


def test_known_optimum_state_to_action_mapping():
    """Learn a = 0.25 + 0.5 x over x in [0, 1]: the greedy error over a grid must fall below 0.05."""
    config = SOMQConfig(input_shape=(10,), action_shape=(10,)).with_overrides(
        {"decay": "inv:500", "n_s": "3", "n_a": "3", "epsilon": "0.3", "p": "0.5"})
    learner = SOMQLearner(config, n_trials=10, seed=1, observation_low=[0], observation_high=[1], action_low=[0],
                   action_high=[1])
    rng = np.random.default_rng(0)
    grid = np.broadcast_to(np.linspace(0, 1, 101)[None, :, None], (10, 101, 1))
    before = np.abs(learner.predict(grid)[..., 0] - (0.25 + 0.5 * grid[..., 0])).mean(axis=1)
    for _ in range(3000):
        x = rng.random((10, 1))
        learner.learn(-np.abs(learner.act(x)[:, 0] - (0.25 + 0.5 * x[:, 0])))
    after = np.abs(learner.predict(grid)[..., 0] - (0.25 + 0.5 * grid[..., 0])).mean(axis=1)
    assert before.mean() > 0.15
    assert after.mean() < 0.05 and after.max() < 0.07  # measured: mean 0.030, max 0.040


def _run(learner, n_steps, seed=0, start=0):
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(start):
        rng.random((learner.n_trials, 2))
    for _ in range(n_steps):
        x = rng.random((learner.n_trials, 2))
        a = learner.act(x)
        out.append(a)
        learner.learn(-np.abs(a - x).sum(axis=1))
    return np.array(out)


def test_determinism_and_seeds():
    a, b, c = (SOMQLearner(SOMQConfig(input_shape=(3, 3), action_shape=(4,)), n_trials=2, seed=s, **BOX2)
               for s in (5, 5, 6))
    ra, rb, rc = _run(a, 30), _run(b, 30), _run(c, 30)
    np.testing.assert_array_equal(ra, rb)
    np.testing.assert_array_equal(a.q, b.q)
    assert not np.array_equal(ra, rc)
    assert not np.array_equal(a.input_weights[0], a.input_weights[1])  # trials are independent


def test_trial_alone_equals_trial_in_batch():
    config = SOMQConfig(input_shape=(4, 2), action_shape=(5,), noise="gaussian")
    batch = SOMQLearner(config, n_trials=5, seed=9, **BOX2)
    alone = SOMQLearner(config, n_trials=1, seed=9, trial_ids=[3], **BOX2)
    rng = np.random.default_rng(1)
    for _ in range(60):
        x = rng.random((5, 2))
        a = batch.act(x)
        np.testing.assert_array_equal(alone.act(x[3:4]), a[3:4])
        r = -np.abs(a).sum(axis=1)
        batch.learn(r)
        alone.learn(r[3:4])
    np.testing.assert_array_equal(alone.q[0], batch.q[3])
    np.testing.assert_array_equal(alone.action_weights[0], batch.action_weights[3])


@pytest.mark.parametrize("mid_step", [False, True], ids=["between_steps", "between_act_and_learn"])
def test_save_load_round_trip(tmp_path, mid_step):
    config = SOMQConfig(input_shape=(3, 2), action_shape=(4,), gamma=0.5,
                        epsilon=Schedule(0.2, ExponentialDecay(0.99), floor=0.01))
    learner = SOMQLearner(config, n_trials=3, seed=4, trial_ids=[4, 0, 9], **BOX2)
    _run(learner, 400)
    if mid_step:
        learner.act(np.full((3, 2), 0.25))
    path = tmp_path / "learner.npz"
    learner.save(path)
    loaded = SOMQLearner.load(path)
    assert loaded.config == config and loaded.t == learner.t == 400 and loaded.seed == 4
    np.testing.assert_array_equal(loaded.trial_ids, [4, 0, 9])
    for name in ("input_weights", "action_weights", "q"):
        np.testing.assert_array_equal(getattr(loaded, name), getattr(learner, name))
    if mid_step:
        for agent in (loaded, learner):
            agent.learn(np.zeros(3), np.zeros((3, 2)), False)
    np.testing.assert_array_equal(_run(loaded, 300, seed=8), _run(learner, 300, seed=8))
    np.testing.assert_array_equal(loaded.q, learner.q)


def test_resume_equals_uninterrupted(tmp_path):
    config = SOMQConfig(input_shape=(5,), action_shape=(4,))
    whole = SOMQLearner(config, n_trials=2, seed=1, **BOX2)
    first = SOMQLearner(config, n_trials=2, seed=1, **BOX2)
    expected = _run(whole, 900)
    got = [_run(first, 600)]
    first.save(tmp_path / "l.npz")
    resumed = SOMQLearner.load(tmp_path / "l.npz")
    got.append(_run(resumed, 300, start=600))
    np.testing.assert_array_equal(np.concatenate(got), expected)
    np.testing.assert_array_equal(resumed.q, whole.q)
    np.testing.assert_array_equal(resumed.action_weights, whole.action_weights)


def test_predict_is_greedy_and_draws_nothing():
    config = SOMQConfig(input_shape=(3, 3), action_shape=(4,))
    a = SOMQLearner(config, n_trials=2, seed=0, **BOX2)
    b = SOMQLearner(config, n_trials=2, seed=0, **BOX2)
    _run(a, 50), _run(b, 50)
    many = np.random.default_rng(0).random((2, 7, 2))
    predicted = a.predict(many)
    assert predicted.shape == (2, 7, 2)
    winners, units = a.greedy_units(many)
    assert winners.shape == units.shape == (2, 7)
    np.testing.assert_array_equal(predicted[1, 4], a.action_weights[1, a.q[1, winners[1, 4]].argmax()])
    np.testing.assert_array_equal(a.predict(many[:, 0]), predicted[:, 0])
    np.testing.assert_array_equal(_run(a, 20), _run(b, 20))  # predict moved no stream


def test_config_dict_round_trip_and_overrides():
    config = SOMQConfig(input_shape=(10, 10), action_shape=(8,), alpha=Schedule(1, InverseDecay(500), 0.1),
                        gamma=0.25, noise="gaussian", input_init=(0.0, 1.0))
    assert SOMQConfig.from_dict(json.loads(json.dumps(config.to_dict()))) == config
    changed = config.with_overrides({
        "decay": "exp:0.9985", "alpha": "0.5", "p.floor": "0.05", "epsilon.scale": "0.3",
        "neighbourhood_q": "false", "input_shape": "30", "action_shape": "30", "gamma": "0.9",
        "noise": "uniform", "n_a.decay": "inv:100", "input_init": "none"})
    others = [name for name in SOMQConfig.SCHEDULES if name != "n_a"]
    assert all(getattr(changed, name).decay == ExponentialDecay(0.9985) for name in others)
    assert changed.n_a.decay == InverseDecay(100)
    assert changed.alpha == Schedule(0.5, ExponentialDecay(0.9985), 0.1)
    assert changed.p.floor == 0.05 and changed.epsilon.scale == 0.3
    assert not changed.neighbourhood_q and changed.input_shape == (30,) and changed.gamma == 0.9
    assert changed.noise == "uniform" and changed.input_init is None


@pytest.mark.parametrize(
    "overrides, match",
    [
        ({"beta": "1"}, "unknown key 'beta'; allowed keys: decay, alpha"),
        ({"alpha.top": "1"}, "unknown key"),
        ({"alpha": "-1"}, "alpha=-1: alpha must be >= 0"),
        ({"n_s": "-2"}, "n_s=-2"),
        ({"p": "1.5"}, "p must be a probability in \\[0, 1\\]"),
        ({"decay": "fast"}, "allowed: inv:TAU"),
        ({"neighbourhood_q": "maybe"}, "neighbourhood_q must be true or false"),
        ({"input_shape": "0x3"}, "input_shape"),
        ({"gamma": "2"}, "gamma must be <= 1"),
        ({"noise": "pink"}, "noise must be 'uniform' or 'gaussian'"),
    ],
)
def test_bad_overrides_one_clear_line(overrides, match):
    with pytest.raises(ValueError, match=match) as info:
        SOMQConfig().with_overrides(overrides)
    assert "\n" not in str(info.value)


@pytest.mark.parametrize(
    "make, match",
    [
        (lambda: SOMQConfig(input_shape=(0,)), "input_shape size must be a whole number >= 1"),
        (lambda: SOMQConfig(action_shape=(5, 0)), "action_shape"),
        (lambda: SOMQConfig(alpha=-0.1), "alpha must be >= 0"),
        (lambda: SOMQConfig(n_a=-1), "n_a must be >= 0"),
        (lambda: SOMQConfig(p=Schedule(1.2)), "p must be a probability"),
        (lambda: SOMQConfig(input_init=(1.0, 0.0)), "input_init"),
        (lambda: SOMQLearner(SOMQConfig(), observation_low=[0, 1], observation_high=[1, 1], action_low=[0],
                      action_high=[1]), "observation bounds need low < high"),
        (lambda: SOMQLearner(SOMQConfig(), observation_low=[0], observation_high=[1], action_low=[0, 0],
                      action_high=[1]), "action high must have shape"),
        (lambda: SOMQLearner(SOMQConfig(), n_trials=0, **BOX2), "n_trials"),
        (lambda: SOMQLearner(SOMQConfig(), seed=-1, **BOX2), "seed"),
        (lambda: SOMQLearner({"alpha": 1}, **BOX2), "config must be a SOMQConfig"),
        (lambda: SOMQConfig(q_init=float("nan")), "q_init must be finite"),
        (lambda: SOMQConfig(action_init="even"), "action_init must be one of random, grid, got 'even'"),
        (lambda: SOMQLearner(SOMQConfig(action_shape=(9,), action_init="grid"), **BOX2),
         "action_init=grid needs an action map with one grid dimension per action dimension: action_shape=9 has 1"),
        (lambda: SOMQConfig(action_init="grid", grid_span=0.0), "grid_span must be in \\(0, 1\\], got 0.0"),
        (lambda: SOMQConfig(action_init="grid", grid_span=1.5), "grid_span must be in \\(0, 1\\], got 1.5"),
        (lambda: SOMQConfig(grid_span=0.5), "grid_span applies only with action_init='grid'"),
    ],
)
def test_bad_construction(make, match):
    with pytest.raises(ValueError, match=match):
        make()


def test_bad_observations_and_rewards_are_rejected_not_clipped():
    learner = SOMQLearner(SOMQConfig(input_shape=(3,), action_shape=(3,)), n_trials=2, **BOX2)
    with pytest.raises(ValueError, match="learn\\(\\) needs a preceding act"):
        learner.learn([0.0, 0.0])
    for bad, match in [([[0.1, 0.2]], "observations must have shape"), ([[0.1, np.nan], [0, 0]], "finite"),
                       ([[0.1, 0.2, 0.3]] * 2, "obs_dim=2"), ([[np.inf, 0], [0, 0]], "finite")]:
        with pytest.raises(ValueError, match=match):
            learner.act(bad)
    before = learner.q.copy()
    learner.act([[0.1, 0.2], [0.3, 0.4]])
    for bad, match in [([0.0, np.nan], "rewards must be finite"), ([0.0], "rewards must have shape"),
                       ([np.inf, 0.0], "finite")]:
        with pytest.raises(ValueError, match=match):
            learner.learn(bad)
    with pytest.raises(ValueError, match="terminal must be a bool"):
        learner.learn([0.0, 0.0], terminal=[1, 0, 1])
    with pytest.raises(ValueError, match="next_observations must"):
        learner.learn([0.0, 0.0], [[0.0, np.nan], [0.0, 0.0]])
    np.testing.assert_array_equal(learner.q, before)  # nothing learned from the bad calls
    learner.learn([0.0, -1.0])
    assert learner.t == 1


def test_conforms_to_protocol_and_exposes_grids_and_parameters():
    learner = SOMQLearner(SOMQConfig(input_shape=(10, 10), action_shape=(8,)), n_trials=3, **BOX2)
    assert isinstance(learner, Learner)
    assert learner.input_grid.shape == (100, 2) and learner.action_grid.shape == (8, 2)
    assert learner.input_weights.shape == (3, 100, 2) and learner.action_weights.shape == (3, 8, 2)
    assert learner.q.shape == (3, 100, 8)
    assert learner.parameters() == {"alpha": 1.0, "lambda_s": 1.0, "lambda_a": 1.0, "n_s": 20.0, "n_a": 20.0,
                                    "p": 1.0, "epsilon": 0.1}
    # Table 1: Q zero, action weights evenly inside the action box, input weights inside the observation box.
    assert (learner.q == 0).all()
    assert (learner.action_weights >= -1).all() and (learner.action_weights <= 1).all()
    assert (learner.input_weights >= 0).all() and (learner.input_weights <= 1).all()


def test_act_copies_the_proposed_action_and_input_init_is_used():
    config = SOMQConfig(input_shape=(4,), action_shape=(5,), epsilon=0.5, input_init=(0.25, 0.5))
    learner = SOMQLearner(config, n_trials=3, seed=1, **BOX2)
    assert learner.input_weights.min() >= 0.25 and learner.input_weights.max() < 0.5
    before = learner.action_weights.copy()
    actions = learner.act(np.full((3, 2), 0.3))  # step 7 (in learn) is the only place the action map may move
    np.testing.assert_array_equal(learner.action_weights, before)
    assert not np.isin(actions, before).any()
    actions[...] = 99.0  # the returned array is the caller's: changing it must not reach the learner
    learner.learn(np.zeros(3))
    assert np.abs(learner.action_weights).max() <= 1.0


def test_relative_epsilon_scales_with_each_action_range():
    box = dict(observation_low=[0.0], observation_high=[1.0], action_low=[0.0, -100.0],
               action_high=[1.0, 100.0])
    steps = []
    for relative in (False, True):
        config = SOMQConfig(input_shape=(1,), action_shape=(1,), p=0.0, epsilon=0.01,
                            epsilon_relative=relative)
        learner = SOMQLearner(config, n_trials=200, seed=0, **box)
        learner.action_weights[...] = [0.5, 0.0]  # far from the bounds: nothing is clipped
        steps.append(np.abs(learner.act(np.zeros((200, 1))) - [0.5, 0.0]))
    assert steps[0].max() <= 0.01 and steps[0][:, 1].max() > 0.009  # absolute: 0.01 in both dimensions
    assert steps[1][:, 0].max() <= 0.01 and steps[1][:, 1].max() <= 2.0 and steps[1][:, 1].max() > 1.8
    np.testing.assert_allclose(steps[1][:, 1], 200 * steps[0][:, 1], rtol=1e-12)  # same draws, scaled
    assert SOMQConfig().with_overrides({"epsilon_relative": "true"}).epsilon_relative


def test_grid_span_spreads_the_grid_over_a_middle_part_of_the_action_box():
    # A 5-unit line over a fifth of [-3, 3] runs from -0.6 to 0.6; a 3 x 3 rectangle over a tenth of
    # [-1, 1] x [0, 1] is centred on (0, 0.5); span 1 is the whole box.
    box = dict(observation_low=[0.0], observation_high=[1.0], action_low=[-3.0], action_high=[3.0])
    narrow = SOMQLearner(SOMQConfig(input_shape=(2,), action_shape=(5,), action_init="grid", grid_span=0.2), **box)
    np.testing.assert_allclose(narrow.action_weights[0, :, 0], [-0.6, -0.3, 0.0, 0.3, 0.6])
    square = grid_actions((3, 3), np.array([-1.0, 0.0]), np.array([1.0, 1.0]), 0.1)
    np.testing.assert_allclose(square[[0, 4, 8]], [[-0.1, 0.45], [0.0, 0.5], [0.1, 0.55]])
    np.testing.assert_allclose(grid_actions((3,), np.array([-1.0]), np.array([1.0])).ravel(), [-1.0, 0.0, 1.0])
    assert SOMQConfig(action_init="grid").with_overrides({"grid_span": "0.25"}).grid_span == 0.25


def test_optimistic_q_init_makes_the_greedy_policy_try_every_action_unit():
    # One state, five action units spread over [0, 1] (the ends on the bounds), no random exploration, rewards
    # in (0, 1]: with Q starting at 0 (the paper's) the first unit tried stays greedy; starting above every
    # return, each unit is tried once before any is tried twice, and the best one is then kept.
    box = dict(observation_low=[0.0], observation_high=[1.0], action_low=[0.0], action_high=[1.0])
    tried = {}
    for q_init in (0.0, 2.0):
        config = SOMQConfig(input_shape=(1,), action_shape=(5,), alpha=1.0, lambda_a=0.0, n_a=0.0, p=0.0,
                            epsilon=0.0, action_init="grid", q_init=q_init)
        learner = SOMQLearner(config, seed=3, **box)
        np.testing.assert_array_equal(learner.action_weights[0, :, 0], [0.0, 0.25, 0.5, 0.75, 1.0])
        assert (learner.q == q_init).all()
        actions = []
        for _ in range(12):
            action = learner.act([[0.5]])
            actions.append(float(action[0, 0]))
            learner.learn(1.0 - np.abs(action[:, 0] - 0.75))
        tried[q_init] = actions
    assert len(set(tried[0.0])) == 1  # never leaves its first unit
    assert sorted(tried[2.0][:5]) == [0.0, 0.25, 0.5, 0.75, 1.0]
    assert tried[2.0][5:] == [0.75] * 7
