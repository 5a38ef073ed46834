"""Replayed steps: each trial's last steps kept after they were learned from, and learned from again.

SOM-Q learns from each step once, when its target is known (step 6 onwards). Where the reward is rare
(dm_control's pendulum-swingup pays only within 8 degrees of upright), the few steps that reached it are
seen once each, and the values that lead to them rise one learning step at a time. Experience replay (Lin
1992, "Self-improving reactive agents based on reinforcement learning, planning and teaching") keeps the
steps and relearns some of them after every new one, so a rare reward is learned from many times and its
value spreads back through the table at the pace of the replays, not of the visits.

A ``Replay`` keeps, per trial, the last ``capacity`` learned steps as they were learned: the observation,
the chosen action unit and its action, the return (the reward, or with n-step targets the n rewards) and
the discount with the observation it bootstraps from (discount 0: no bootstrap). A replayed step is
learned from as a new one is (the target ``return + discount max_a Q(s', a)`` with today's Q, and Q's step
8 over both neighbourhoods, with each map's nearest units found again on today's input maps) but moves no
map: the maps follow the states and actions as they come, and a replay moves only Q.

Which steps are replayed comes from the learner's random row of the step (one number per replay: the
slot ``floor(u * size)`` of the trial's kept steps, uniformly), so a trial alone replays what it
replays in a batch.
"""

from __future__ import annotations

import numpy as np

__all__ = ["Replay"]


class Replay:
    """Each trial's last ``capacity`` learned steps in a ring (``capacity`` 0: nothing kept).

    Args:
      capacity: the steps kept per trial (the oldest is overwritten when full).
      n_trials, obs_dim, action_dim: the learner's sizes.
    """

    #: The arrays a learner saves and restores, by attribute name.
    ARRAYS = ("observations", "chosen", "actions", "returns", "discounts", "next_observations", "count")

    def __init__(self, capacity: int, *, n_trials: int, obs_dim: int, action_dim: int) -> None:
        self.capacity = capacity
        self.observations = np.zeros((capacity, n_trials, obs_dim))
        self.chosen = np.zeros((capacity, n_trials), dtype=np.int64)
        self.actions = np.zeros((capacity, n_trials, action_dim))
        self.returns = np.zeros((capacity, n_trials))
        self.discounts = np.zeros((capacity, n_trials))
        self.next_observations = np.zeros((capacity, n_trials, obs_dim))
        self.count = np.zeros(n_trials if capacity else 0, dtype=np.int64)  #: steps ever kept, per trial
        self._trials = np.arange(n_trials)

    @staticmethod
    def floats(capacity: int, *, n_trials: int, obs_dim: int, action_dim: int) -> int:
        """The numbers a replay of these sizes holds (for a learner's memory estimate)."""
        return capacity * n_trials * (2 * obs_dim + action_dim + 3) + (n_trials if capacity else 0)

    @property
    def sizes(self) -> np.ndarray:
        """The steps each trial holds now, ``(n_trials,)``."""
        return np.minimum(self.count, self.capacity)

    def push(self, active, returns, discounts, observations, chosen, actions, next_observations) -> None:
        """Keep the step just learned from in each ``active`` trial (a learn kernel's arguments for it)."""
        trials = self._trials[active]
        if not self.capacity or not trials.size:
            return
        slot = self.count[trials] % self.capacity
        self.observations[slot, trials] = observations[trials]
        self.chosen[slot, trials] = chosen[trials]
        self.actions[slot, trials] = actions[trials]
        self.returns[slot, trials] = returns[trials]
        self.discounts[slot, trials] = discounts[trials]
        self.next_observations[slot, trials] = next_observations[trials]
        self.count[trials] += 1

    def sample(self, numbers: np.ndarray) -> tuple[np.ndarray, ...]:
        """The steps that ``numbers`` (one uniform [0, 1) number per trial) pick, uniformly over each trial's
        kept steps: ``(active, returns, discounts, observations, chosen, actions, next_observations)``, each with
        the trials first; a trial that holds no step yet is not active."""
        sizes = self.sizes
        active = sizes > 0
        slot = np.minimum((numbers * sizes).astype(np.int64), np.maximum(sizes - 1, 0))
        trials = self._trials
        return (active, self.returns[slot, trials], self.discounts[slot, trials], self.observations[slot, trials],
                self.chosen[slot, trials], self.actions[slot, trials], self.next_observations[slot, trials])
