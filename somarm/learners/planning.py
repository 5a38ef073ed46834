"""Planning over the maps' cells: a model of what each pair of units led to, solved for Q.

SOM-Q learns Q from each step once, one learning step at a time. Where the reward is rare and the road
to it long (dm_control's pendulum-swingup pays only within 8 degrees of upright, after several swings),
the values that lead there rise slowly and the map's few steps near the goal are seen once each. A
model of the map's cells learns faster from the same steps (Dyna, Sutton 1990): every step taught the
pair it tried, the input map's nearest unit and the chosen action unit, what followed. A ``CellModel``
keeps, per trial and pair, how often the pair was tried, the rewards it was paid, and how often it led
to each input unit (counted only where the step bootstraps: a termination leads nowhere). Every
``plan_every`` steps the learner solves the model by value iteration (``plan`` sweeps of
``Q(s, a) = mean reward + gamma * sum_s' P(s' | s, a) max_a' Q(s', a')``, from today's Q) and writes the
result into Q. A pair never tried keeps ``q_init``: with an optimistic ``q_init`` the greedy policy goes
where the model is unknown, and the model tells it how to get there (optimism under uncertainty, as
R-max, Brafman and Tennenholtz 2002).

The input map's units are the model's states, so the model is as good as the cells are: its counts are of
units as they stand, and a map that keeps moving (``lambda_s`` > 0) shifts the cells under them; the
``input_placement="grid"`` map with ``lambda_s=0`` gives fixed cells (the variable resolution of Munos and
Moore 2002, at one resolution). The model is per trial, so a trial alone plans what it plans in a batch.
"""

from __future__ import annotations

import numpy as np

__all__ = ["CellModel"]


class CellModel:
    """Each trial's counts of its map's pairs of units (``n_units`` input units x ``n_actions`` action units).

    Args:
      n_trials, n_units, n_actions: the learner's sizes; ``n_units`` 0 keeps nothing (no planning).
    """

    #: The arrays a learner saves and restores, by attribute name.
    ARRAYS = ("tries", "paid", "led")

    def __init__(self, *, n_trials: int, n_units: int, n_actions: int) -> None:
        pairs = n_units * n_actions
        self.tries = np.zeros((n_trials, n_units, n_actions) if pairs else (0, 0, 0))  #: steps of each pair
        self.paid = np.zeros_like(self.tries)  #: rewards summed, per pair
        # How often each pair led to each input unit (bootstrapped steps only), as float32: whole counts up
        # to 2**24 are exact, and the table is the model's bulk (n_units**2 x n_actions per trial).
        self.led = np.zeros((n_trials, pairs, n_units) if pairs else (0, 0, 0), dtype=np.float32)

    @staticmethod
    def floats(*, n_trials: int, n_units: int, n_actions: int) -> float:
        """The 8-byte numbers a model of these sizes takes (for a learner's memory estimate)."""
        return n_trials * n_units * n_actions * (2 + n_units / 2)

    @property
    def active(self) -> bool:
        return self.tries.size > 0

    def push(self, trials: np.ndarray, units: np.ndarray, chosen: np.ndarray, rewards: np.ndarray,
             bootstrap: np.ndarray, next_units: np.ndarray) -> None:
        """Count one step of each trial in ``trials`` (a bool mask): the pair it tried (``units``,
        ``chosen``), its reward and, where it ``bootstrap``s, the unit it led to (``next_units``)."""
        n_actions = self.tries.shape[2]
        for trial in np.flatnonzero(trials):
            s, a = units[trial], chosen[trial]
            self.tries[trial, s, a] += 1.0
            self.paid[trial, s, a] += rewards[trial]
            if bootstrap[trial]:
                self.led[trial, s * n_actions + a, next_units[trial]] += 1.0

    def solve(self, q: np.ndarray, *, gamma: float, q_init: float, sweeps: int) -> None:
        """Write into ``q`` (``(n_trials, n_units, n_actions)``) the model's values after ``sweeps`` sweeps
        of value iteration from ``q``'s own; untried pairs get ``q_init``."""
        n_trials, n_units, n_actions = self.tries.shape
        for trial in range(n_trials):
            tried = self.tries[trial] > 0
            if not tried.any():
                continue
            tries = np.maximum(self.tries[trial], 1.0)
            mean_reward = self.paid[trial] / tries
            # P(s' | s, a) over the transitions seen (short of 1 where steps ended): a pair leads to few units,
            # so the sweeps run over those alone, in a fixed order
            pairs, nexts = np.nonzero(self.led[trial])
            chances = self.led[trial][pairs, nexts] / tries.reshape(-1)[pairs]
            values = np.where(tried, q[trial], q_init)
            for _ in range(sweeps):
                ahead = np.bincount(pairs, weights=chances * values.max(axis=1)[nexts], minlength=n_units * n_actions)
                values = np.where(tried, mean_reward + gamma * ahead.reshape(n_units, n_actions), q_init)
            q[trial] = values
