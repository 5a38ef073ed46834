"""Greedy evaluation of an episodic task: whole episodes, their return, success and length."""

import numpy as np
import pytest

from somarm.run import evaluation, greedy_cost

STEP_LIMIT = 20


class _TwoTrials:
    """A learner stand-in with two trials: the policy does not matter to the planted episodes."""

    n_trials = 2

    def predict(self, observations):
        return np.zeros_like(observations)


class _PlantedEpisodes:
    """An episodic task whose 2 x 100 episodes are planted: trial 0 reaches the goal once (in 4 steps)
    and is cut at the step limit 99 times; trial 1 reaches it every time in 4 steps."""

    name, episodic = "planted", True

    def sample_starts(self, rng, n):
        return np.zeros((n, 2))

    def run_episodes(self, policy, starts):
        assert policy(starts).shape == starts.shape == (200, 2)
        length = np.full(200, 4)
        length[1:100] = STEP_LIMIT
        success = length < STEP_LIMIT
        return {"success": success, "length": length, "returns": -1.5 * length}


def test_mean_episode_length_counts_a_failed_episode_at_the_step_limit():
    episodes = evaluation.greedy_episodes(_TwoTrials(), _PlantedEpisodes(), n_episodes=100)
    np.testing.assert_allclose(episodes["success_rate"], [0.01, 1.0])
    # One success in 100: near the step limit, not the one successful episode's 4 steps.
    np.testing.assert_allclose(episodes["mean_length"], [(4 + 99 * STEP_LIMIT) / 100, 4.0])
    assert episodes["mean_length"][0] > 0.95 * STEP_LIMIT
    np.testing.assert_allclose(episodes["mean_return"], -1.5 * episodes["mean_length"])


def test_a_run_is_ranked_by_its_return_when_episodic_and_by_its_one_step_reward_otherwise():
    assert greedy_cost({"greedy_mean_return": -5.5, "greedy_sd_return": 0.5, "greedy_success_rate": 1.0}) == (5.5, 0.5)
    assert greedy_cost({"greedy_mean_reward": -0.03, "greedy_sd_reward": 0.01}) == (0.03, 0.01)


@pytest.mark.parametrize("task_name", ["reach2", "throw_distance"])
def test_scoring_in_slices_gives_the_rewards_of_one_batch_bit_for_bit(task_name, monkeypatch):
    from somarm import run
    from somarm.run import evaluation

    result = run.train(run.RunConfig(task=task_name, n_trials=3, n_steps=300), progress=False)
    whole = evaluation.evaluate_greedy(result.learner, result.task, n_observations=50, seed=4)
    monkeypatch.setattr(evaluation, "_CHUNK_ELEMENTS", 7)  # 2 observations of 3 trials at a time
    sliced = evaluation.evaluate_greedy(result.learner, result.task, n_observations=50, seed=4)
    np.testing.assert_array_equal(sliced, whole)
