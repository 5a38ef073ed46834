import json

import numpy as np
import pytest

from somarm.learners.motoric import MotoricConfig, MotoricMap
from somarm.protocols import Learner

BOX1 = dict(observation_low=[0.0], observation_high=[3.0], action_low=[0.0, 0.0], action_high=[1.0, 1.0])
BOX2 = dict(observation_low=[0.0, 0.0], observation_high=[1.0, 1.0], action_low=[-1.0, -1.0],
            action_high=[1.0, 1.0])


def _planted(neighbourhood_values=True):
    config = MotoricConfig(input_shape=(3,), alpha=0.5, lambda_s=0.5, lambda_a=0.5, n_s=1.0, n_a=1.0,
                           epsilon=0.0, neighbourhood_values=neighbourhood_values)
    learner = MotoricMap(config, **BOX1)
    learner.input_weights[0] = [[0.0], [1.0], [2.0]]
    learner.action_weights[0] = [[0.0, 0.0], [0.5, 0.5], [1.0, 1.0]]
    learner.values[0] = [-1.0, -0.5, -1.0]
    return learner


def test_one_update_with_planted_weights_exact_arrays():
    learner = _planted()
    np.testing.assert_array_equal(learner.act([[1.25]]), [[0.5, 0.5]])  # s_1's private action, epsilon 0
    learner.learn([0.5])  # 0.5 > V(s_1) = -0.5: the private actions move, shared over the input grid
    np.testing.assert_array_equal(learner.action_weights[0], [[0.125, 0.125], [0.5, 0.5], [0.875, 0.875]])
    np.testing.assert_array_equal(learner.values[0], [-0.625, 0.0, -0.625])
    np.testing.assert_array_equal(learner.input_weights[0], [[0.3125], [1.125], [1.8125]])


def test_no_improvement_keeps_actions_and_private_values():
    learner = _planted(neighbourhood_values=False)
    before = learner.action_weights.copy()
    learner.act([[1.25]])
    learner.learn([-2.0])
    np.testing.assert_array_equal(learner.action_weights, before)
    np.testing.assert_array_equal(learner.values[0], [-1.0, -0.5 + 0.5 * -1.5, -1.0])


def test_delayed_reward_bootstraps():
    config = MotoricConfig(input_shape=(3,), alpha=1.0, lambda_s=0.0, lambda_a=0.0, n_s=0.0, n_a=0.0,
                           epsilon=0.0, gamma=0.5, neighbourhood_values=False)
    learner = MotoricMap(config, **BOX1)
    learner.input_weights[0] = [[0.0], [1.0], [2.0]]
    learner.values[0] = [0.0, -1.0, 4.0]
    learner.act([[0.9]])
    learner.learn([1.0], [[2.2]], False)
    assert learner.values[0, 1] == 3.0
    learner.act([[0.9]])
    learner.learn([1.0], [[2.2]], True)
    assert learner.values[0, 1] == 1.0


def test_known_optimum_state_to_action_mapping():
    """Learn a = 0.25 + 0.5 x over x in [0, 1]: the greedy error over a grid must fall below 0.03."""
    config = MotoricConfig(input_shape=(10,)).with_overrides(
        {"decay": "inv:500", "n_s": "3", "n_a": "2", "epsilon": "0.3", "alpha.floor": "0",
         "lambda_a.floor": "0", "epsilon.floor": "0"})
    learner = MotoricMap(config, n_trials=10, seed=1, observation_low=[0], observation_high=[1],
                         action_low=[0], action_high=[1])
    rng = np.random.default_rng(0)
    grid = np.broadcast_to(np.linspace(0, 1, 101)[None, :, None], (10, 101, 1))
    before = np.abs(learner.predict(grid)[..., 0] - (0.25 + 0.5 * grid[..., 0])).mean(axis=1)
    for _ in range(2000):
        x = rng.random((10, 1))
        learner.learn(-np.abs(learner.act(x)[:, 0] - (0.25 + 0.5 * x[:, 0])))
    after = np.abs(learner.predict(grid)[..., 0] - (0.25 + 0.5 * grid[..., 0])).mean(axis=1)
    assert before.mean() > 0.15
    assert after.mean() < 0.03 and after.max() < 0.04  # measured at 3000 steps: mean 0.014, max 0.015


def _run(learner, n_steps, seed=0):
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(n_steps):
        x = rng.random((learner.n_trials, 2))
        a = learner.act(x)
        out.append(a)
        x_next, done = rng.random((learner.n_trials, 2)), rng.random(learner.n_trials) < 0.5
        learner.learn(-np.abs(a - x).sum(axis=1), x_next, done)
    return np.array(out)


def test_trial_alone_equals_trial_in_batch_and_determinism():
    config = MotoricConfig(input_shape=(3, 3), noise="gaussian", gamma=0.7)
    batch = MotoricMap(config, n_trials=4, seed=2, **BOX2)
    again = MotoricMap(config, n_trials=4, seed=2, **BOX2)
    alone = MotoricMap(config, n_trials=1, seed=2, trial_ids=[2], **BOX2)
    rng = np.random.default_rng(5)
    for _ in range(80):
        x, x_next, done = rng.random((4, 2)), rng.random((4, 2)), rng.random(4) < 0.3
        a = batch.act(x)
        np.testing.assert_array_equal(again.act(x), a)
        np.testing.assert_array_equal(alone.act(x[2:3]), a[2:3])
        r = -np.abs(a).sum(axis=1)
        batch.learn(r, x_next, done)
        again.learn(r, x_next, done)
        alone.learn(r[2:3], x_next[2:3], done[2:3])
    np.testing.assert_array_equal(alone.action_weights[0], batch.action_weights[2])
    np.testing.assert_array_equal(alone.values[0], batch.values[2])
    assert not np.array_equal(batch.action_weights[0], batch.action_weights[1])


def test_save_load_resume_equals_uninterrupted(tmp_path):
    config = MotoricConfig(input_shape=(4,), gamma=0.3)
    whole = MotoricMap(config, n_trials=2, seed=3, **BOX2)
    part = MotoricMap(config, n_trials=2, seed=3, **BOX2)
    _run(whole, 600)
    _run(part, 600)
    part.save(tmp_path / "m.npz")
    loaded = MotoricMap.load(tmp_path / "m.npz")
    assert loaded.config == config and loaded.t == 600
    np.testing.assert_array_equal(_run(loaded, 100, seed=1), _run(whole, 100, seed=1))
    np.testing.assert_array_equal(loaded.values, whole.values)


def test_config_round_trip_overrides_and_errors():
    config = MotoricConfig()
    assert MotoricConfig.from_dict(json.loads(json.dumps(config.to_dict()))) == config
    changed = config.with_overrides({"neighbourhood_values": "false", "n_a": "0", "input_shape": "20"})
    assert not changed.neighbourhood_values and changed.n_a.scale == 0 and changed.input_shape == (20,)
    with pytest.raises(ValueError, match="unknown key 'p'; allowed keys: decay, alpha"):
        config.with_overrides({"p": "0.5"})
    with pytest.raises(ValueError, match="epsilon must be >= 0"):
        MotoricConfig(epsilon=-1.0)
    learner = MotoricMap(config, **BOX2)
    with pytest.raises(ValueError, match="finite"):
        learner.act([[np.nan, 0.0]])
    with pytest.raises(ValueError, match="preceding act"):
        learner.learn([0.0])


def test_protocol_shapes_and_predict():
    learner = MotoricMap(MotoricConfig(), n_trials=3, **BOX2)
    assert isinstance(learner, Learner)
    assert learner.action_weights.shape == (3, 100, 2) and learner.values.shape == (3, 100)
    assert "p" not in learner.parameters() and learner.parameters()["n_s"] == 10.0
    x = np.random.default_rng(0).random((3, 5, 2))
    winners, units = learner.greedy_units(x)
    np.testing.assert_array_equal(winners, units)
    np.testing.assert_array_equal(learner.predict(x)[2, 3], learner.action_weights[2, winners[2, 3]])
