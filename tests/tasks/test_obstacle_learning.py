"""Delayed reward pays on reach2_obstacle: gamma 0.9 goes around the wall, gamma 0 stays stuck at it."""

from __future__ import annotations

import numpy as np
import pytest

from somarm import run as runs
from somarm.run import evaluation
from somarm.tasks import obstacle_search


def _greedy(gamma: float) -> dict[str, np.ndarray]:
    config = runs.RunConfig(task="reach2_obstacle", n_trials=2, n_steps=12_000, seed=0,
                                overrides={"gamma": gamma})
    result = runs.train(config, progress=False)
    return evaluation.greedy_episodes(result.learner, result.task, n_episodes=50, seed=0)


@pytest.mark.slow
def test_gamma_09_reaches_the_goal_in_90_percent_of_greedy_episodes_and_gamma_0_in_few():
    # Bound: this project's target (>= 90% from the start distribution) after 12,000 steps (a little over
    # half the preset's run); the shortest path takes 4 steps, so greedy episodes may take at most 10.
    discounted = _greedy(0.9)
    assert (discounted["success_rate"] >= 0.9).all(), discounted
    assert (discounted["mean_length"] <= 10).all(), discounted
    # gamma = 0 learns the next reward only, which leads into the wall: at most 1 episode in 10.
    myopic = _greedy(0.0)
    assert (myopic["success_rate"] <= 0.1).all(), myopic


@pytest.mark.slow
def test_random_target_changes_reach_the_goal_in_fewer_than_half_of_the_episodes():
    from somarm import tasks

    task = tasks.make("reach2_obstacle")
    starts = task.sample_observations(evaluation.evaluation_rng(0), 200)
    episodes = task.run_episodes(obstacle_search.random_policy(task, np.random.default_rng(0)), starts)
    assert 0.0 < episodes["success"].mean() < 0.5
