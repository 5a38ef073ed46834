"""n-step targets (``n_step``, ``somarm.learners.trail``): what waits, when it is learned from, and towards what."""

import numpy as np
import pytest
from somq_cases import BOX4, batch_and_alone, drive_episodes, small_config

from somarm.learners.schedules import Schedule
from somarm.learners.somq import SOMQConfig, SOMQLearner
from somarm.learners.trail import Trail

BOX2 = dict(observation_low=[0.0, 0.0], observation_high=[1.0, 1.0], action_low=[-1.0], action_high=[1.0])
GAMMA = 0.5


def _recorder(n_step):
    """A learner whose Q of the step's own unit becomes its target exactly: alpha 1, no neighbourhood, fixed
    maps, one action unit; its 2x2 input units sit on the corners of the unit box."""
    config = SOMQConfig(input_shape=(2, 2), action_shape=(1,), alpha=Schedule(1.0), lambda_s=Schedule(0.0),
                        lambda_a=Schedule(0.0), n_s=Schedule(0.0), n_a=Schedule(0.0), p=Schedule(0.0),
                        epsilon=Schedule(0.0), gamma=GAMMA, neighbourhood_q=False, n_step=n_step)
    learner = SOMQLearner(config, n_trials=1, seed=0, **BOX2)
    learner.input_weights[0] = [[0.0, 0.0], [0.0, 1.0], [1.0, 0.0], [1.0, 1.0]]
    return learner


CORNERS = np.array([[0.0, 0.0], [0.0, 1.0], [1.0, 0.0], [1.0, 1.0]])


def _walk(learner, path, rewards, terminal_at=None):
    """Step along ``path`` (corner indices, the last one only reached), learning ``rewards``."""
    for t, r in enumerate(rewards):
        learner.act(CORNERS[path[t]][None])
        learner.learn([r], CORNERS[path[t + 1]][None], np.array([t == terminal_at]))


def test_a_step_is_learned_n_steps_later_towards_the_n_rewards_and_the_discounted_value_n_steps_on():
    learner = _recorder(3)
    learner.q[0, 3, 0] = 8.0  # the value of the corner the walk reaches after three steps
    _walk(learner, [0, 1, 2, 3], [1.0, 2.0, 4.0])
    expected = 1.0 + GAMMA * 2.0 + GAMMA ** 2 * 4.0 + GAMMA ** 3 * 8.0
    assert learner.q[0, 0, 0] == pytest.approx(expected)
    assert learner.q[0, 1, 0] == 0.0 and learner.q[0, 2, 0] == 0.0  # still waiting: fewer than 3 steps on
    assert learner._trail.count.tolist() == [2]


def test_with_one_step_the_target_is_the_papers_reward_and_discounted_next_value():
    learner = _recorder(1)
    learner.q[0, 1, 0] = 8.0
    _walk(learner, [0, 1], [1.0])
    assert learner.q[0, 0, 0] == pytest.approx(1.0 + GAMMA * 8.0)
    assert learner._trail.observations.shape[0] == 0  # nothing kept


def test_a_terminal_step_ends_every_wait_with_the_rewards_to_the_end_alone():
    learner = _recorder(4)
    learner.q[0, 3, 0] = 100.0  # never read: the episode ends there
    _walk(learner, [0, 1, 2, 3], [1.0, 2.0, 4.0], terminal_at=2)
    assert learner.q[0, :3, 0] == pytest.approx([1.0 + GAMMA * 2.0 + GAMMA ** 2 * 4.0, 2.0 + GAMMA * 4.0, 4.0])
    assert learner._trail.count.tolist() == [0]


def test_a_broken_chain_bootstraps_each_waiting_step_from_the_last_next_observation_over_the_steps_it_had():
    learner = _recorder(4)
    learner.q[0, 3, 0] = 8.0
    _walk(learner, [0, 1, 3], [1.0, 2.0])  # a time limit after two steps: not terminal, ends at corner 3
    assert learner.q[0, 0, 0] == 0.0 and learner._trail.count.tolist() == [2]
    learner.act(CORNERS[[2]])  # a new episode starts elsewhere
    assert learner.q[0, 0, 0] == pytest.approx(1.0 + GAMMA * 2.0 + GAMMA ** 2 * 8.0)
    assert learner.q[0, 1, 0] == pytest.approx(2.0 + GAMMA * 8.0)
    assert learner._trail.count.tolist() == [0]


def test_an_unbroken_chain_keeps_waiting_when_the_next_act_continues_it():
    learner = _recorder(4)
    _walk(learner, [0, 1, 3], [1.0, 2.0])
    learner.act(CORNERS[[3]])
    assert learner._trail.count.tolist() == [2] and not learner.q.any()


def test_the_rounds_sum_each_trials_own_rewards_and_discount_by_its_own_steps():
    trail = Trail(3, GAMMA, n_trials=2, obs_dim=1, action_dim=1, n_groups=1, k=1)
    zeros = np.zeros((2, 1, 1))
    for r in ([1.0, 10.0], [2.0, 20.0]):
        trail.push(np.zeros((2, 1)), zeros.astype(np.int64), zeros, np.zeros(2, dtype=np.int64), np.zeros((2, 1)),
                   np.array(r), np.zeros((2, 1)))
    rounds = list(trail.rounds(np.array([2, 1]), np.array([True, False])))
    assert len(rounds) == 2
    active, returns, discounts = rounds[0][:3]
    assert active.tolist() == [True, True]
    assert returns.tolist() == [1.0 + GAMMA * 2.0, 10.0 + GAMMA * 20.0]
    assert discounts[0] == GAMMA ** 2 and discounts[1] == 0.0
    active, returns, discounts = rounds[1][:3]
    assert active.tolist() == [True, False] and returns[0] == 2.0 and discounts[0] == GAMMA
    assert trail.count.tolist() == [0, 1] and trail.rewards[0, 1] == 20.0  # the second trial's newer step stays


@pytest.mark.parametrize("changes", [{"n_step": 3}, {"n_step": 5, "input_groups": "pairs", "k_nearest": 2},
                                     {"n_step": 2, "input_groups": "pairs", "local_linear": True,
                                      "shared_slopes": True, "response": "interpolated"}])
def test_a_trial_alone_equals_the_same_trial_in_a_batch_with_n_step_targets(changes):
    batch, alone = batch_and_alone(small_config((3, 3), True, 0.8).with_changes(changes), drive_episodes, 150)
    for name in ("input_weights", "action_weights", "q", "slopes", "_trail_rewards", "_trail_phi", "_trail_count"):
        np.testing.assert_array_equal(_trial(getattr(batch, name), name, 2), _trial(getattr(alone, name), name, 0))
    assert batch.q.any()


def _trial(array, name, trial):
    """One trial's part of a learner's array (the trail's arrays hold the slot first, then the trial)."""
    slot_first = name.startswith("_trail_") and name[len("_trail_"):] not in ("last", "count")
    return array[:, trial] if slot_first else array[trial]


def test_n_step_targets_learn_other_values_than_one_step_targets():
    one, three = (SOMQLearner(small_config((3, 3), True, 0.8).with_changes({"n_step": n, "k_nearest": 2}),
                              n_trials=1, seed=2, **BOX4) for n in (1, 3))
    drive_episodes(one, 60)
    drive_episodes(three, 60)
    assert not np.allclose(one.q, three.q)


def test_save_and_load_between_act_and_learn_continue_the_waiting_steps_exactly(tmp_path):
    config = small_config((3,), True, 0.8).with_changes({"n_step": 4, "input_groups": "pairs"})
    a = SOMQLearner(config, n_trials=2, seed=4, **BOX4)
    drive_episodes(a, 30)
    a.act(a._trail.last.copy())  # the chains go on: the steps keep waiting
    assert a._trail.count.any()
    a.save(tmp_path / "l.npz")
    b = SOMQLearner.load(tmp_path / "l.npz")
    np.testing.assert_array_equal(a._trail.count, b._trail.count)
    for learner in (a, b):
        learner.learn([1.0, 0.0], np.full((2, 4), 0.2), np.array([False, True]))
        drive_episodes(learner, 10)
    for name in ("input_weights", "action_weights", "q", "_trail_observations", "_trail_count"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name))


@pytest.mark.parametrize("changes, message", [
    ({"n_step": 0}, "n_step must be a whole number >= 1"),
    ({"n_step": 2.5}, "n_step must be a whole number >= 1"),
    ({"n_step": 3, "gamma": 0.0}, "it needs gamma > 0, got gamma=0"),
    ({"n_step": 3, "grow_every": 100}, "it needs grow_every=0"),
])
def test_a_bad_n_step_is_refused_in_one_line(changes, message):
    base = {"gamma": 0.9, **changes}
    with pytest.raises(ValueError, match=message):
        SOMQConfig(**base)


def test_n_step_runs_the_grouped_kernels_and_one_is_the_papers_path():
    assert SOMQConfig(gamma=0.9, n_step=2).grouped and not SOMQConfig(gamma=0.9).grouped


@pytest.mark.parametrize("name, value, message", [
    ("_trail_count", 7, "_trail_count must hold 0 to 3 waiting steps"),
    ("_trail_units", 10_000, "_trail_units must name input units"),
    ("_trail_chosen", -1, "_trail_units must name input units .* and _trail_chosen action units"),
])
def test_a_learner_file_with_waiting_steps_out_of_range_is_refused_in_one_line(tmp_path, name, value, message):
    learner = SOMQLearner(small_config((3,), True, 0.8).with_changes({"n_step": 4, "input_groups": "pairs"}),
                          n_trials=2, seed=4, **BOX4)
    drive_episodes(learner, 30)
    learner.save(tmp_path / "l.npz")
    arrays = dict(np.load(tmp_path / "l.npz", allow_pickle=False))
    arrays[name] = np.full_like(arrays[name], value)
    np.savez(tmp_path / "damaged.npz", **arrays)
    with pytest.raises(ValueError, match=rf"^{tmp_path / 'damaged.npz'} is a damaged learner file: {message}") as caught:
        SOMQLearner.load(tmp_path / "damaged.npz")
    assert "\n" not in str(caught.value)
