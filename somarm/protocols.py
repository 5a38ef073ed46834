"""The two contracts data flows through: task -> observation -> learner -> action -> task.

A learner never sees a task and a task never sees a learner; the experiment runner, the
evaluation and the viewer hold one of each and pass arrays between them.
"""

from __future__ import annotations

from typing import Protocol, runtime_checkable

import numpy as np

__all__ = ["Learner", "BatchedTask"]


@runtime_checkable
class Learner(Protocol):
    """What every learner (SOM-Q, Motoric Map) offers, batched over independent trials."""

    n_trials: int
    t: int  #: steps learned so far (the t of the annealing schedules)

    def act(self, observations: np.ndarray) -> np.ndarray:
        """Exploring action for each trial: ``(n_trials, obs_dim) -> (n_trials, action_dim)``."""

    def learn(
        self,
        rewards: np.ndarray,
        next_observations: np.ndarray | None = None,
        terminal: bool | np.ndarray = True,
    ) -> None:
        """Learn from the rewards ``(n_trials,)`` that followed the last ``act``."""

    def predict(self, observations: np.ndarray) -> np.ndarray:
        """Greedy actions, no exploration, no learning.

        ``(n_trials, obs_dim) -> (n_trials, action_dim)`` or
        ``(n_trials, n_obs, obs_dim) -> (n_trials, n_obs, action_dim)``.
        """

    def save(self, path) -> None:
        """Write the whole state (config, maps, values, step, random streams) atomically."""


@runtime_checkable
class BatchedTask(Protocol):
    """A one-step-episode task evaluated for ``n_trials`` independent trials in one call."""

    name: str
    n_trials: int
    observation_low: np.ndarray  #: (obs_dim,)
    observation_high: np.ndarray  #: (obs_dim,)
    action_low: np.ndarray  #: (action_dim,)
    action_high: np.ndarray  #: (action_dim,)
    action_periodic: np.ndarray  #: (action_dim,) bools: angles whose low and high are one pose

    def reset(self) -> np.ndarray:
        """Start a new episode in every trial; returns observations ``(n_trials, obs_dim)``."""

    def step(self, actions: np.ndarray) -> np.ndarray:
        """Apply ``(n_trials, action_dim)`` actions; returns rewards ``(n_trials,)``."""

    def evaluate(self, observations: np.ndarray, actions: np.ndarray) -> np.ndarray:
        """Rewards for given observations and actions, ``(..., obs_dim), (..., action_dim) -> (...)``.

        Deterministic and stateless: no episode counter moves, no random number is drawn.
        """

    def sample_observations(self, rng: np.random.Generator, n: int) -> np.ndarray:
        """``n`` fresh observations from the task's distribution, shape ``(n, obs_dim)``."""
