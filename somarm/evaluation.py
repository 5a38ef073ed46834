"""Greedy evaluation: any learner with ``predict`` on fresh observations of any batched task."""

from __future__ import annotations

import numpy as np

from somarm.protocols import BatchedTask, Learner
from somarm.streams import PURPOSES
from somarm.validation import check_int

__all__ = ["evaluation_rng", "evaluate_greedy"]


def evaluation_rng(seed: int) -> np.random.Generator:
    """The generator for evaluation observations: its own stream, apart from training's."""
    check_int("seed", seed, minimum=0)
    return np.random.Generator(
        np.random.PCG64(np.random.SeedSequence(int(seed), spawn_key=(PURPOSES["evaluation"],)))
    )


def evaluate_greedy(
    learner: Learner, task: BatchedTask, *, n_observations: int = 1000, seed: int = 0
) -> np.ndarray:
    """Mean reward of each trial's greedy policy on the same fresh observations.

    Args:
      learner: a trained learner with ``n_trials`` trials.
      task: a task with the same number of trials (its current phase is used).
      n_observations: fresh observations drawn from the task's distribution (>= 1).
      seed: seed of the evaluation stream (independent of training's streams).

    Returns:
      Mean reward per trial, shape ``(n_trials,)``.
    """
    n_observations = check_int("n_observations", n_observations)
    observations = task.sample_observations(evaluation_rng(seed), n_observations)
    batch = np.broadcast_to(observations, (learner.n_trials, *observations.shape))
    actions = learner.predict(np.ascontiguousarray(batch))
    return task.evaluate(batch, actions).mean(axis=-1)
