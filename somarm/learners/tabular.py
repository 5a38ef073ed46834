"""A fixed-action tabular Q-learner: the alternative Smith (2002) discusses to adaptive maps.

The observation box is cut into a fixed grid of equal cells and each action dimension into
``action_bins`` equal intervals whose centres are the only actions; a Q-table joins cells and
actions. Batched like SOM-Q: ``q (n_trials, n_cells, n_actions)``, one agent is ``n_trials == 1``,
and trial i draws from its own stream (seed, trial i), so it is the same alone or in a batch.
Rules:

- an observation's cell is found per dimension, ``floor((x - low) / (high - low) * bins)``,
  kept inside the grid (an observation on the upper bound belongs to the last cell);
- epsilon-greedy: with probability epsilon(t) a uniformly random action, else the greedy one;
- greedy = the best Q among the actions tried in that cell (untried actions have no estimate,
  so they are never greedy); ties, and cells where nothing was tried, go to the lowest index;
- Q is the sample mean of the returns seen (``alpha=None``, rate 1/n) or moves by a constant
  rate ``alpha``; the return is the reward, plus ``gamma * max Q(next cell)`` for a trial that
  is not terminal;
- random numbers: one row per step per trial, ``[explore?, random action]``.

The table grows as ``action_bins ** action_dim``: with 20 joint angles (``reach20``) even two
values per joint give 10^6 actions, which is why a fixed grid cannot stand in for SOM-Q there.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from somarm.learners.base import ConfigBase, LearnerBase
from somarm.learners.schedules import InverseDecay, Schedule
from somarm.validation import check_int, check_number

__all__ = ["TabularConfig", "TabularQ", "MAX_TABLE_ENTRIES"]

#: Largest Q-table per trial (cells x actions); two such tables (Q and counts) of 8 bytes each.
MAX_TABLE_ENTRIES = 10_000_000


@dataclass(frozen=True)
class TabularConfig(ConfigBase):
    """Everything that defines a tabular learner; the defaults suit the 2-D tasks."""

    observation_bins: int = 16
    """Cells per observation dimension (the grid has ``observation_bins ** obs_dim`` cells)."""
    action_bins: int = 16
    """Actions per action dimension: the centres of equal intervals (``action_bins ** action_dim`` actions)."""
    epsilon: Schedule = Schedule(1.0, InverseDecay(1000.0))
    """Probability of a random action; the default anneals as SOM-Q's p in Table 1."""
    alpha: float | None = None
    """Q's learning rate: None = the sample mean (rate 1/n); a number in (0, 1] = a constant rate."""
    gamma: float = 0.0
    """Discount in [0, 1]; 0 = the immediate reward of the paper's tasks."""

    SCHEDULES = ("epsilon",)

    def __post_init__(self) -> None:
        check_int("observation_bins", self.observation_bins)
        check_int("action_bins", self.action_bins)
        epsilon = self.epsilon if isinstance(self.epsilon, Schedule) else Schedule(
            check_number("epsilon", self.epsilon, minimum=0.0))
        if max(epsilon.scale, epsilon.floor) > 1.0:
            raise ValueError(f"epsilon must be a probability in [0, 1], got {epsilon!r}")
        object.__setattr__(self, "epsilon", epsilon)
        if self.alpha is not None:
            check_number("alpha", self.alpha, minimum=0.0, maximum=1.0, strict_minimum=True)
        check_number("gamma", self.gamma, minimum=0.0, maximum=1.0)

    @classmethod
    def from_table(cls, table: Any) -> TabularConfig:
        """The tabular counterpart of a paper table (a ``SOMQConfig``): its p explores, its gamma discounts.

        SOM-Q's epsilon is a perturbation size, not an exploration probability, so it is not taken.
        """
        return cls(epsilon=table.p, gamma=table.gamma)


class TabularQ(LearnerBase):
    """Tabular Q-learning over fixed grids for ``n_trials`` trials (``somarm.protocols.Learner``).

    Args:
      config: a ``TabularConfig``.
      observation_low, observation_high: the observation box, ``(obs_dim,)`` each.
      action_low, action_high: the action box, ``(action_dim,)`` each.
      action_periodic: which action dimensions are angles, ``(action_dim,)`` bools (saved, not used:
        the grid's cells are the same whether or not an angle wraps).
      n_trials: independent trials advanced together (>= 1).
      seed: the run's seed. trial_ids: which trials of the run these are (``[7]`` replays trial 7).

    Raises:
      ValueError: a bad config or bounds, or a table above ``MAX_TABLE_ENTRIES`` (one line).
    """

    kind = "tabular"
    config_class = TabularConfig
    learned_arrays = ("q",)
    _STATE_ARRAYS = ("q", "counts")
    _PENDING_ARRAYS = ("_cells", "_choices")
    _MEMORY_HINT = "use fewer bins or fewer trials"

    @classmethod
    def memory_needed(cls, config: TabularConfig, *, n_trials: int, obs_dim: int,
                      action_dim: int) -> tuple[str, float]:
        """Per trial Q and the visit counts (8 bytes an entry each), and the action table.

        Raises:
          ValueError: a table above ``MAX_TABLE_ENTRIES`` per trial (one line).
        """
        n_cells = config.observation_bins ** obs_dim
        n_actions = config.action_bins ** action_dim
        if n_cells * n_actions > MAX_TABLE_ENTRIES:
            raise ValueError(
                f"a tabular learner with {config.action_bins} values per action dimension over {action_dim} "
                f"dimensions has {float(n_actions):.3g} actions x {n_cells} observation cells = "
                f"{float(n_cells) * n_actions:.3g} table entries; at most {MAX_TABLE_ENTRIES:.0e} are allowed "
                f"(use fewer bins, or somq, whose action map does not grow with the dimension)")
        n_floats = n_trials * 2 * n_cells * n_actions + n_actions * action_dim
        return (f"a tabular learner with observation_bins={config.observation_bins}, action_bins="
                f"{config.action_bins} and {n_trials} trial(s)", 8.0 * n_floats)

    def _build(self) -> None:
        config, obs_dim, action_dim = self.config, self.obs_dim, self.action_dim
        self._cell_strides = config.observation_bins ** np.arange(obs_dim - 1, -1, -1, dtype=np.int64)
        n_cells = config.observation_bins ** obs_dim
        n_actions = config.action_bins ** action_dim
        # Action k's values: its per-dimension indices (C order) at the interval centres.
        centres = (np.arange(config.action_bins) + 0.5) / config.action_bins
        index = np.indices((config.action_bins,) * action_dim).reshape(action_dim, -1).T
        self.actions = self.action_low + (self.action_high - self.action_low) * centres[index]
        self.q = np.zeros((self.n_trials, n_cells, n_actions))
        self.counts = np.zeros((self.n_trials, n_cells, n_actions), dtype=np.int64)
        self._cells = np.zeros(self.n_trials, dtype=np.int64)
        self._choices = np.zeros(self.n_trials, dtype=np.int64)
        self._rows = np.arange(self.n_trials)
        self._open_streams(2)

    @property
    def n_cells(self) -> int:
        return self.q.shape[1]

    @property
    def n_actions(self) -> int:
        return self.q.shape[2]

    def cells(self, observations) -> np.ndarray:
        """The grid cell of each observation: ``(n_trials, [n_obs,] obs_dim) -> (n_trials, [n_obs])``.

        Raises:
          ValueError: a wrong shape, NaN or inf.
        """
        x = np.asarray(observations, dtype=np.float64)
        n, d = self.n_trials, self.observation_low.size
        if x.ndim not in (2, 3) or x.shape[0] != n or x.shape[-1] != d:
            raise ValueError(f"observations must have shape (n_trials, obs_dim) or (n_trials, n_obs, obs_dim) "
                             f"with n_trials={n}, obs_dim={d}, got {x.shape}")
        if not np.isfinite(x).all():
            raise ValueError("observations must be finite, got NaN or inf")
        bins = self.config.observation_bins
        fraction = (x - self.observation_low) / (self.observation_high - self.observation_low)
        per_dim = np.floor(fraction * bins).astype(np.int64)
        np.clip(per_dim, 0, bins - 1, out=per_dim)
        return per_dim @ self._cell_strides  # the C-order index of the cell

    def _greedy(self, cells: np.ndarray) -> np.ndarray:
        """Best tried action of each cell ``(n_trials, ...) -> (n_trials, ...)``; see the module rules."""
        rows = self._rows.reshape((-1,) + (1,) * (cells.ndim - 1))
        q = np.where(self.counts[rows, cells] > 0, self.q[rows, cells], -np.inf)
        return np.argmax(q, axis=-1)

    def act(self, observations) -> np.ndarray:
        """An epsilon-greedy action per trial: ``(n_trials, obs_dim) -> (n_trials, action_dim)``."""
        cells = self.cells(observations)
        if cells.ndim != 1:
            raise ValueError(f"act takes one observation per trial, shape ({self.n_trials}, obs_dim)")
        rows = self._streams.next()
        explore = rows[:, 0] < self.config.epsilon.value(self.t)
        random = np.minimum((rows[:, 1] * self.n_actions).astype(np.int64), self.n_actions - 1)
        self._cells[:] = cells
        self._choices[:] = np.where(explore, random, self._greedy(cells))
        self._pending = True
        return self.actions[self._choices]

    def learn(self, rewards, next_observations=None, terminal: bool | np.ndarray = True) -> None:
        """Update Q of the last ``act``'s cells and actions with ``rewards (n_trials,)``.

        Raises:
          ValueError: no ``act`` before, a bad shape, NaN or inf, or a missing ``next_observations``.
        """
        if not self._pending:
            raise ValueError("learn() needs a preceding act(): call act(observations) first")
        r = np.asarray(rewards, dtype=np.float64)
        if r.shape != (self.n_trials,) or not np.isfinite(r).all():
            raise ValueError(f"rewards must be {self.n_trials} finite numbers, shape ({self.n_trials},), "
                             f"got shape {r.shape}")
        done = np.broadcast_to(np.asarray(terminal, dtype=bool), (self.n_trials,))
        target = r.copy()
        if self.config.gamma > 0.0 and not done.all():
            if next_observations is None:
                raise ValueError("next_observations (n_trials, obs_dim) are needed when gamma > 0 and a "
                                 "trial is not terminal")
            cells = self.cells(next_observations)
            best = self.q[self._rows, cells, self._greedy(cells)]
            target += np.where(done, 0.0, self.config.gamma * best)
        index = (self._rows, self._cells, self._choices)
        self.counts[index] += 1
        rate = 1.0 / self.counts[index] if self.config.alpha is None else self.config.alpha
        self.q[index] += rate * (target - self.q[index])
        self._pending = False
        self.t += 1

    def predict(self, observations) -> np.ndarray:
        """Greedy actions: ``(n_trials, [n_obs,] obs_dim) -> (n_trials, [n_obs,] action_dim)``; nothing drawn."""
        return self.actions[self._greedy(self.cells(observations))]
