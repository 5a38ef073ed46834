"""The Motoric Map baseline (graph B of Fig. 13): an input SOM whose units each keep one action.

Smith describes it in one sentence: "the input space is again mapped with a SOM, but ... each
input unit maintains a single, private action which is learned in the same way as the proposed
model - i.e. by using random noise as exploration". The rules this project chose where that is
brief (none of them is the paper's):

1. The winner s_j of the observation is found as in SOM-Q (squared Euclidean distance).
2. Its private action is COPIED and perturbed exactly as SOM-Q's step 4 (random(-1, 1) x epsilon,
   or Gaussian; epsilon optionally relative to each action range), then kept inside the action
   bounds. There is no choice between units, so no p.
3. Each input unit keeps a value estimate V (initially 0), the counterpart of SOM-Q's Q(s_j, a_k).
   If ``r + gamma * V(s'_j) > V(s_j)`` the private actions move towards the perturbed action with
   rate ``lambda_A * psi_S(j, m, N_A)``: the neighbourhood is taken on the INPUT grid (as in Ritter,
   Martinetz and Schulten's motor maps, where neighbouring units share output learning), with its
   own width N_A. N_A = 0 keeps the actions strictly private.
4. V moves towards the corrected return by ``alpha * psi_S(j, m, N_S)`` (or at s_j alone when
   ``neighbourhood_values`` is False), then the input map moves towards the observation.

Random numbers: one row per step per trial holding the noise (action_dim numbers, or two per
dimension for Gaussian noise); initial weights as SOM-Q (input weights, then one action per unit).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np

from somarm.learners.base import ConfigBase, validate_common
from somarm.learners.maps import MapLearner, grid_floats, shape_text
from somarm.learners.schedules import InverseDecay, Schedule
from somarm.learners.som import distances_from, neighbourhood, update, winners

__all__ = ["MotoricConfig", "MotoricMap"]

_F = InverseDecay(500.0)


@dataclass(frozen=True)
class MotoricConfig(ConfigBase):
    """Everything that defines a Motoric Map; the defaults are Table 2's numbers.

    ``somarm.learners.presets.get_motoric("table2")`` is Fig. 13 B's config: these defaults with the input
    weights starting in [0, 1] as Table 1 says.
    """

    input_shape: tuple[int, ...] = (10, 10)
    """Input map grid: ``(n,)`` or ``(rows, cols)``; one private action per unit."""
    alpha: Schedule = Schedule(1.0, _F, 0.1)
    """Learning rate of the value estimates."""
    lambda_s: Schedule = Schedule(1.0, _F)
    """Learning rate of the input map."""
    lambda_a: Schedule = Schedule(1.0, _F, 0.1)
    """Learning rate of the private actions."""
    n_s: Schedule = Schedule(10.0, _F)
    """Input map neighbourhood size (also the value neighbourhood)."""
    n_a: Schedule = Schedule(3.0, _F)
    """Neighbourhood size, on the input grid, over which an improving action is shared (0 = private)."""
    epsilon: Schedule = Schedule(0.1, _F, 0.01)
    """Largest perturbation of each action element (the standard deviation for Gaussian noise)."""
    gamma: float = 0.0
    """Discount in [0, 1]; 0 = immediate reward."""
    neighbourhood_values: bool = True
    """Update the value estimates of neighbouring units too (the counterpart of +NL)."""
    noise: Literal["uniform", "gaussian"] = "uniform"
    """Perturbation: ``uniform`` random(-1, 1) x epsilon, or ``gaussian`` N(0, 1) x epsilon."""
    epsilon_relative: bool = False
    """Read epsilon as a fraction of each action dimension's range (high - low) instead of in action units."""
    input_init: tuple[float, float] | None = None
    """Range of the initial input weights in every dimension; None = the observation bounds."""

    SCHEDULES = ("alpha", "lambda_s", "lambda_a", "n_s", "n_a", "epsilon")

    def __post_init__(self) -> None:
        validate_common(self)

    @classmethod
    def from_table(cls, table: Any) -> MotoricConfig:
        """The counterpart of a SOM-Q table: every shared number kept, N_A on the input grid,
        ``neighbourhood_values`` as the table's ``neighbourhood_q``."""
        shared = {field.name for field in dataclasses.fields(cls)} & set(table.to_dict())
        values = {name: getattr(table, name) for name in shared}
        return cls(**values, neighbourhood_values=table.neighbourhood_q)


class MotoricMap(MapLearner):
    """The Motoric Map for ``n_trials`` independent trials (conforms to ``somarm.protocols.Learner``).

    Same keywords and verbs as ``somarm.learners.somq.SOMQLearner``. ``action_weights`` is
    ``(n_trials, n_input_units, action_dim)`` (one private action per input unit), ``values`` is
    ``(n_trials, n_input_units)``, and ``action_grid`` is the input grid.
    """

    kind = "motoric"
    config_class = MotoricConfig
    learned_arrays = ("input_weights", "action_weights", "values")
    _STATE_ARRAYS = learned_arrays

    @classmethod
    def memory_needed(cls, config: MotoricConfig, *, n_trials: int, obs_dim: int,
                      action_dim: int) -> tuple[str, float]:
        """The input grid's coordinates, and per trial the input weights, private actions and values."""
        n_s = int(np.prod(config.input_shape))
        n_floats = grid_floats(config.input_shape) + n_trials * (n_s * obs_dim + n_s * action_dim + n_s)
        return (f"a motoric learner with input_shape={shape_text(config.input_shape)} and {n_trials} trial(s)",
                8.0 * n_floats)

    def _build_maps(self) -> None:
        n_units = self.input_grid.shape[0]
        self.action_grid = self.input_grid
        self.action_weights = np.empty((self.n_trials, n_units, self.action_dim))
        for trial, rng in enumerate(self._initial_generators()):
            self.input_weights[trial] = self._initial_input_weights(rng)
            span = self.action_high - self.action_low
            self.action_weights[trial] = self.action_low + span * rng.random((n_units, self.action_dim))
        self.values = np.zeros((self.n_trials, n_units))
        self._gaussian = self.config.noise == "gaussian"
        self._open_streams(self.action_dim * (2 if self._gaussian else 1))
        self._rows = np.arange(self.n_trials)

    def act(self, observations) -> np.ndarray:
        """An exploring action per trial: ``(n_trials, obs_dim) -> (n_trials, action_dim)``.

        Raises:
          ValueError: wrong shape, NaN or inf; or the previous act() still waits for its learn().
        """
        self._check_not_pending()
        x = self._check_observations(observations)
        uniforms = self._streams.next()
        if self._gaussian:
            u1, u2 = uniforms[:, 0::2], uniforms[:, 1::2]
            noise = np.sqrt(-2.0 * np.log1p(-u1)) * np.cos(2.0 * np.pi * u2)
        else:
            noise = 2.0 * uniforms - 1.0
        self._observations[...] = x
        self._winners[...] = winners(self.input_weights, x)
        self._units[...] = self._winners
        proposed = self.action_weights[self._rows, self._winners]  # fancy indexing: a copy
        perturbed = proposed + noise * self._epsilons(self.config.epsilon.value(self.t))
        self._actions[...] = np.minimum(np.maximum(perturbed, self.action_low), self.action_high)
        self._pending = True
        return self._actions.copy()

    def learn(self, rewards, next_observations=None, terminal: bool | np.ndarray = True) -> None:
        """Learn from the rewards ``(n_trials,)`` that followed the last ``act``.

        Args:
          rewards: ``(n_trials,)``, finite.
          next_observations: ``(n_trials, obs_dim)``; needed when gamma > 0 and a trial is not terminal.
          terminal: bool or ``(n_trials,)`` bools; terminal trials do not bootstrap.

        Raises:
          ValueError: no ``act`` before, bad shapes, NaN or inf, or missing ``next_observations``.
        """
        r, bootstrap, x_next = self._check_learn(rewards, next_observations, terminal)
        values, cfg, t, j = self.values, self.config, self.t, self._winners
        target = r.copy()
        if bootstrap.any():
            j_next = winners(self.input_weights, x_next)
            target = np.where(bootstrap, r + cfg.gamma * values[self._rows, j_next], r)
        improved = target > values[self._rows, j]
        if improved.any():
            update(self.action_weights, self._actions, j, cfg.lambda_a.value(t), cfg.n_a.value(t),
                   self.input_grid, mask=improved)
        alpha = cfg.alpha.value(t)
        if cfg.neighbourhood_values:
            rates = alpha * neighbourhood(distances_from(self.input_grid, j), cfg.n_s.value(t))
            values += rates * (target[:, None] - values)
        else:
            values[self._rows, j] += alpha * (target - values[self._rows, j])
        update(self.input_weights, self._observations, j, cfg.lambda_s.value(t), cfg.n_s.value(t),
               self.input_grid)
        self._pending = False
        self.t += 1

    def greedy_units(self, observations) -> tuple[np.ndarray, np.ndarray]:
        """The winning input unit, twice: its own private action is the one taken.

        Args:
          observations: ``(n_trials, obs_dim)`` or ``(n_trials, n_obs, obs_dim)``.

        Returns:
          ``(input_winners, action_units)``, equal arrays of the leading shape of ``observations``.
        """
        x = self._check_observations(observations, allow_many=True)
        input_winners = winners(self.input_weights, x)
        return input_winners, input_winners.copy()

    def predict(self, observations) -> np.ndarray:
        """Greedy actions (the winners' private actions), no exploration, no learning.

        Returns:
          ``(n_trials, action_dim)`` or ``(n_trials, n_obs, action_dim)``.
        """
        units, _ = self.greedy_units(observations)
        index = np.arange(self.n_trials).reshape((-1,) + (1,) * (units.ndim - 1))
        return self.action_weights[index, units]
