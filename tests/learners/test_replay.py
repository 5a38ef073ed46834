"""Replayed steps (``replay``, ``somarm.learners.replay``): what is kept, what is picked, what a replay moves, and
that a rare reward's value spreads back sooner with it."""

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

from somarm.learners.replay import Replay
from somarm.learners.somq import SOMQConfig, SOMQLearner, row_width


def _push(replay, returns, active=(True, True)):
    n = len(returns)
    replay.push(np.array(active), np.array(returns, dtype=float), np.full(n, 0.5), np.zeros((n, 2)),
                np.arange(n), np.zeros((n, 1)), np.ones((n, 2)))


def test_the_ring_keeps_each_trials_last_steps_and_overwrites_the_oldest():
    replay = Replay(3, n_trials=2, obs_dim=2, action_dim=1)
    for r in range(4):
        _push(replay, [r, 10 + r], active=(True, r < 2))
    assert replay.count.tolist() == [4, 2] and replay.sizes.tolist() == [3, 2]
    assert sorted(replay.returns[:, 0]) == [1.0, 2.0, 3.0]  # step 0 overwritten by step 3
    assert replay.returns[:2, 1].tolist() == [10.0, 11.0]


def test_a_number_picks_a_kept_step_uniformly_and_an_empty_trial_is_not_active():
    replay = Replay(4, n_trials=2, obs_dim=2, action_dim=1)
    for r in range(2):
        _push(replay, [r, 0.0], active=(True, False))
    active, returns, discounts, *_ = replay.sample(np.array([0.49, 0.3]))
    assert active.tolist() == [True, False] and returns[0] == 0.0 and discounts[0] == 0.5
    assert replay.sample(np.array([0.5, 0.3]))[1][0] == 1.0
    assert replay.sample(np.array([0.999999, 0.3]))[1][0] == 1.0


def test_each_replay_takes_one_number_of_the_steps_row():
    config = SOMQConfig(gamma=0.9, replay=5)
    assert row_width(config, 2) == row_width(SOMQConfig(gamma=0.9), 2) + 5


def test_a_replay_moves_q_alone_never_a_map():
    learner = SOMQLearner(small_config((3, 3), True, 0.8).with_changes({"replay": 2, "input_groups": "pairs"}),
                          n_trials=2, seed=3, **BOX4)
    drive_episodes(learner, 40)
    maps = learner.input_weights.copy(), learner.action_weights.copy()
    q = learner.q.copy()
    learner._replay_rounds(learner._current())
    np.testing.assert_array_equal(learner.input_weights, maps[0])
    np.testing.assert_array_equal(learner.action_weights, maps[1])
    assert not np.array_equal(learner.q, q)


@pytest.mark.parametrize("changes", [{"replay": 3}, {"replay": 2, "n_step": 3, "input_groups": "pairs", "k_nearest": 2},
                                     {"replay": 1, "replay_capacity": 7, "local_linear": True, "shared_slopes": True}])
def test_a_trial_alone_equals_the_same_trial_in_a_batch_with_replay(changes):
    batch, alone = batch_and_alone(small_config((3, 3), True, 0.8).with_changes(changes), drive_episodes, 150)
    for name in ("input_weights", "action_weights", "q", "slopes", "_replay_count"):
        np.testing.assert_array_equal(getattr(batch, name)[2], getattr(alone, name)[0])
    np.testing.assert_array_equal(batch._replay_returns[:, 2], alone._replay_returns[:, 0])
    assert batch._replay.sizes.min() > 0


def test_save_and_load_between_act_and_learn_continue_the_replays_exactly(tmp_path):
    config = small_config((3,), True, 0.8).with_changes({"replay": 3, "n_step": 2, "input_groups": "pairs"})
    saved_between_act_and_learn_goes_on_alike(config, drive_episodes, tmp_path,
                                              ("q", "_replay_observations", "_replay_returns", "_replay_count"),
                                              acting_on=lambda learner: learner._trail.last.copy())


def test_replay_spreads_a_rare_rewards_value_back_to_the_start_sooner():
    with_replay, without = chain_start_values({"replay": 4}, 600), chain_start_values({}, 600)
    assert (with_replay >= 0.8).all(), with_replay  # every trial knows the start's value within a fifth
    assert (without >= 0.8).sum() <= 4, without  # learning each step once: half the trials at most


@pytest.mark.parametrize("changes, message", [
    ({"replay": -1}, "replay must be a whole number >= 0"),
    ({"replay": 1.5}, "replay must be a whole number >= 0"),
    ({"replay_capacity": 0}, "replay_capacity must be a whole number >= 1"),
    ({"replay": 2, "grow_every": 100}, "replay applies to maps of a fixed size: it needs grow_every=0"),
])
def test_a_bad_replay_is_refused_in_one_line(changes, message):
    with pytest.raises(ValueError, match=message):
        SOMQConfig(**changes)


def test_replay_runs_the_grouped_kernels_and_none_is_the_papers_path():
    assert SOMQConfig(replay=1).grouped and not SOMQConfig().grouped


def test_a_learner_file_with_a_kept_step_out_of_range_is_refused_in_one_line(tmp_path):
    learner = SOMQLearner(small_config((3,), True, 0.8).with_changes({"replay": 1}), n_trials=2, seed=4, **BOX4)
    drive_episodes(learner, 10)
    learner.save(tmp_path / "l.npz")
    arrays = dict(np.load(tmp_path / "l.npz", allow_pickle=False))
    arrays["_replay_chosen"] = np.full_like(arrays["_replay_chosen"], 99)
    np.savez(tmp_path / "damaged.npz", **arrays)
    with pytest.raises(ValueError, match="is a damaged learner file: _replay_count must be >= 0 and _replay_chosen "
                                         "must name action units 0 to 6") as caught:
        SOMQLearner.load(tmp_path / "damaged.npz")
    assert "\n" not in str(caught.value)


def test_the_memory_estimate_covers_the_kept_steps():
    from somarm import learners

    config = small_config((3, 3), True, 0.8).with_changes({"replay": 2, "replay_capacity": 500, "n_step": 3})
    _, n_bytes = learners.memory_needed("somq", config, n_trials=3, obs_dim=4, action_dim=2)
    learner = SOMQLearner(config, n_trials=3, seed=0, **BOX4)
    held = held_bytes(learner)
    kept = sum(getattr(learner, "_replay_" + name).nbytes for name in Replay.ARRAYS)
    assert kept >= 500 * 3 * (2 * 4 + 2 + 3) * 8 and held <= n_bytes + 64 * (3 + 4 + 2)
