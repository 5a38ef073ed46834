"""n-step targets: each trial's last n steps, waiting until the rewards that follow them are known.

SOM-Q's target (step 6) is the one-step ``r + gamma max_a Q(s', a)``. Where an action changes the reward
only through the states it leads to (Reacher-v5 scores the distance before the step moves the arm), that
target holds the action's effect only in the small difference between the next states' values, which a map
of coarse cells blurs. The n-step target ``r_t + gamma r_(t+1) + ... + gamma^(n-1) r_(t+n-1) + gamma^n max_a
Q(s_(t+n), a)`` carries the rewards the action led to themselves (Watkins 1989, ch. 7; the uncorrected
n-step return of Rainbow, Hessel et al. 2018): the step is learned from n steps after it was taken.

A ``Trail`` keeps, per trial, the steps that wait, oldest first, with what ``act`` left for ``learn`` (the
observation, each map's nearest units and their weights, the chosen action unit and the action) and the
reward. A step is learned from when one of these ends its wait:

- n steps have followed it: the n-step target above;
- its episode ended at a terminal state: every waiting step takes the discounted rewards to the end alone;
- the chain broke: the next ``act`` sees an observation that is not the last ``learn``'s next observation
  (a new episode after a time limit, or any restart). Every waiting step bootstraps from that last next
  observation, over the steps it had: ``sum_(i >= j) gamma^(i - j) r_i + gamma^(c - j) max_a Q(s_last, a)``.

``rounds`` gives the updates as rounds over the trials, oldest step first, each round one call of the
grouped learn kernel with a per-trial return, discount (0: no bootstrap) and mask.
"""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np

__all__ = ["Trail", "Round"]

#: One call of the learn kernel: ``(active, returns, discounts, observations, units, phi, chosen, actions)``.
Round = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]


class Trail:
    """Each trial's waiting steps (``n - 1`` at most between calls), oldest first in slots 0, 1, ...

    Args:
      n: the steps a target looks ahead (n >= 1; with n = 1 no step waits and nothing is kept).
      gamma: the discount.
      n_trials, obs_dim, action_dim: the learner's sizes; n_groups, k: the grouped maps' ``(G, k)`` features.
    """

    def __init__(self, n: int, gamma: float, *, n_trials: int, obs_dim: int, action_dim: int, n_groups: int,
                 k: int) -> None:
        self.n, self.gamma = n, gamma
        slots = n if n > 1 else 0
        self.observations = np.zeros((slots, n_trials, obs_dim))
        self.units = np.zeros((slots, n_trials, n_groups, k), dtype=np.int64)
        self.phi = np.zeros((slots, n_trials, n_groups, k))
        self.chosen = np.zeros((slots, n_trials), dtype=np.int64)
        self.actions = np.zeros((slots, n_trials, action_dim))
        self.rewards = np.zeros((slots, n_trials))
        self.last = np.zeros((n_trials if slots else 0, obs_dim))  #: each trial's last next observation
        self.count = np.zeros(n_trials if slots else 0, dtype=np.int64)  #: each trial's waiting steps
        self._trials = np.arange(n_trials)
        self._powers = gamma ** np.arange(n + 1)

    #: The arrays a learner saves and restores, by attribute name.
    ARRAYS = ("observations", "units", "phi", "chosen", "actions", "rewards", "last", "count")

    @staticmethod
    def floats(n: int, *, n_trials: int, obs_dim: int, action_dim: int, n_groups: int, k: int) -> int:
        """The numbers a trail of these sizes holds (for a learner's memory estimate)."""
        if n <= 1:
            return 0
        return n * n_trials * (obs_dim + 2 * n_groups * k + action_dim + 2) + n_trials * (obs_dim + 1)

    def push(self, observations, units, phi, chosen, actions, rewards, next_observations) -> None:
        """Add the step just taken in every trial (the arrays of one ``act`` and its ``learn``)."""
        slot, trials = self.count, self._trials
        self.observations[slot, trials] = observations
        self.units[slot, trials] = units
        self.phi[slot, trials] = phi
        self.chosen[slot, trials] = chosen
        self.actions[slot, trials] = actions
        self.rewards[slot, trials] = rewards
        self.last[...] = next_observations
        self.count += 1

    def due_after_learn(self, bootstrap: np.ndarray) -> np.ndarray:
        """How many of each trial's oldest steps end their wait after a ``learn``: all of them where the
        episode ended at a terminal state (``bootstrap`` False), the oldest where n steps have followed it."""
        return np.where(bootstrap, (self.count == self.n).astype(np.int64), self.count)

    def due_before_act(self, observations: np.ndarray) -> np.ndarray:
        """How many steps end their wait before an ``act`` on ``observations``: every waiting step of the
        trials whose chain broke (the observation is not the last next observation), else none."""
        broken = (observations != self.last).any(axis=1)
        return np.where(broken, self.count, 0)

    def rounds(self, due: np.ndarray, bootstrap: np.ndarray) -> Iterator[Round]:
        """The updates of the ``due`` oldest steps of each trial, oldest first, one round per slot; the steps
        bootstrap from ``last`` where ``bootstrap`` (else they take their rewards alone). The steps leave the
        trail when the rounds are done."""
        count = self.count
        for j in range(int(due.max(initial=0))):
            active = due > j
            returns = np.zeros(count.shape)
            for i in range(self.n - 1, j - 1, -1):  # sum_(i >= j) gamma^(i - j) r_i over each trial's steps
                returns = np.where(i < count, self.rewards[i] + self.gamma * returns, returns)
            steps = np.maximum(count - j, 0)
            discounts = np.where(bootstrap, self._powers[np.minimum(steps, self.n)], 0.0)
            yield (active, returns, discounts, self.observations[j], self.units[j], self.phi[j], self.chosen[j],
                   self.actions[j])
        self._drop(due)

    def _drop(self, due: np.ndarray) -> None:
        """Remove each trial's ``due`` oldest steps, moving the rest to the front (the trials that drop d steps
        together: slots past a trial's count hold nothing it reads, so they move with the rest)."""
        for d in np.unique(due[due > 0]):
            trials = due == d
            for array in (self.observations, self.units, self.phi, self.chosen, self.actions, self.rewards):
                array[:self.n - d, trials] = array[d:, trials]
        self.count -= due
