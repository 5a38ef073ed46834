"""What the map learners (SOM-Q and the Motoric Map) share: the input map and the step checks.

``MapLearner`` builds the input SOM (grid coordinates, weights), keeps what ``act`` leaves for
``learn`` (observations, winners, chosen units, perturbed actions), checks observations, rewards
and episode ends, refuses an epsilon that would overflow, and counts the grids' memory. A map
learner adds its own action side in ``_build`` and the verbs.
"""

from __future__ import annotations

import abc

import numpy as np

from somarm.learners.base import LearnerBase, initial_generator
from somarm.learners.som import grid_coordinates, grid_offsets

__all__ = ["MapLearner", "grid_floats", "shape_text"]


def grid_floats(shape: tuple[int, ...]) -> int:
    """Floats a map's grid takes: its ``(units, 2)`` coordinates and its ``grid_offsets``, one distance
    per unit. Grid distances are never stored as a ``(units, units)`` matrix."""
    return int(np.prod(shape)) * 3


def shape_text(shape: tuple[int, ...]) -> str:
    """A map shape as the user writes it: ``(10, 10) -> "10x10"``."""
    return "x".join(map(str, shape))


class MapLearner(LearnerBase):
    """A learner with an input SOM: SOM-Q and the Motoric Map (``has_maps``)."""

    has_maps = True
    _PENDING_ARRAYS = ("_observations", "_winners", "_units", "_actions")

    def _build(self) -> None:
        self._check_epsilon()
        self.input_grid = grid_coordinates(self.config.input_shape)
        self._offsets_s = grid_offsets(self.config.input_shape)
        self.input_weights = np.empty((self.n_trials, self.input_grid.shape[0], self.obs_dim))
        # What act() leaves for learn(): observations, winners, chosen units, perturbed actions.
        self._observations = np.zeros((self.n_trials, self.obs_dim))
        self._winners = np.zeros(self.n_trials, dtype=np.int64)
        self._units = np.zeros(self.n_trials, dtype=np.int64)
        self._actions = np.zeros((self.n_trials, self.action_dim))
        self._no_bootstrap = np.zeros(self.n_trials, dtype=np.bool_)
        self._epsilon_buffer = np.empty(self.action_dim)
        self._build_maps()

    @abc.abstractmethod
    def _build_maps(self) -> None:
        """Fill the input weights and make the learner's action side, values and random streams."""

    @abc.abstractmethod
    def greedy_units(self, observations) -> tuple[np.ndarray, np.ndarray]:
        """Winning input unit and greedy action unit of each observation."""

    def _check_epsilon(self) -> None:
        """Refuse, before allocating, an epsilon whose perturbed actions overflow."""
        largest = max(self.config.epsilon.scale, self.config.epsilon.floor)
        span = np.max(self.action_high - self.action_low) if self.config.epsilon_relative else 1.0
        with np.errstate(over="ignore"):  # a perturbed action: up to a few epsilons from a bound
            if not np.isfinite(largest * span * 4.0 + np.max(np.abs([self.action_low, self.action_high]))):
                raise ValueError(f"epsilon={largest:g} is too large: a perturbed action overflows; "
                                 "give a number of the size of the action range")

    def _initial_generators(self) -> list[np.random.Generator]:
        return [initial_generator(self.seed, trial_id) for trial_id in self.trial_ids]

    def _initial_input_weights(self, rng: np.random.Generator) -> np.ndarray:
        low, high = self.observation_low, self.observation_high
        if self.config.input_init is not None:
            low = np.full_like(low, self.config.input_init[0])
            high = np.full_like(high, self.config.input_init[1])
        return low + (high - low) * rng.random((self.input_grid.shape[0], self.obs_dim))

    # -- checks (lean: see ``LearnerBase._floats``; with ``finite=False`` the NaN/inf scan is left
    # to the compiled kernel, which does it before it changes anything) -------------------------
    def _check_observations(self, observations, *, allow_many=False, name="observations",
                            finite=True) -> np.ndarray:
        x = self._floats(name, observations)
        n, d = self.n_trials, self.obs_dim
        if not (x.shape == (n, d) or (allow_many and x.ndim == 3 and x.shape[0] == n and x.shape[2] == d)):
            shape = "(n_trials, obs_dim)" + (" or (n_trials, n_obs, obs_dim)" if allow_many else "")
            raise ValueError(f"{name} must have shape {shape} with n_trials={n}, obs_dim={d}, got {x.shape}")
        if finite and not np.isfinite(x).all():
            raise ValueError(f"{name} must be finite, got NaN or inf")
        return x

    def _check_learn(self, rewards, next_observations, terminal, *, finite=True):
        """``(rewards, bootstrap, next_observations)`` checked; see ``_check_observations`` for ``finite``."""
        if not self._pending:
            raise ValueError("learn() needs a preceding act(): call act(observations) first")
        r = self._floats("rewards", rewards)
        if r.shape != (self.n_trials,):
            raise ValueError(f"rewards must have shape (n_trials,) = ({self.n_trials},), got {r.shape}")
        if finite and not np.isfinite(r).all():
            raise ValueError("rewards must be finite, got NaN or inf")
        if terminal is True:
            bootstrap = self._no_bootstrap
        else:
            done = np.asarray(terminal)
            if done.dtype != np.bool_ or done.shape not in ((), (self.n_trials,)):
                raise ValueError(f"terminal must be a bool or {self.n_trials} bools, got {terminal!r}")
            bootstrap = self._no_bootstrap
            if self.config.gamma > 0.0:
                bootstrap = ~np.broadcast_to(done, (self.n_trials,))
        if next_observations is None:
            if bootstrap is not self._no_bootstrap and bootstrap.any():
                raise ValueError("next_observations (n_trials, obs_dim) are needed when gamma > 0 and "
                                 "a trial is not terminal")
            return r, bootstrap, self._observations
        x_next = self._check_observations(next_observations, name="next_observations", finite=finite)
        return r, bootstrap, x_next

    def _epsilons(self, epsilon: float) -> np.ndarray:
        """The perturbation scale of each action dimension, ``(action_dim,)``."""
        if self.config.epsilon_relative:
            return epsilon * (self.action_high - self.action_low)
        self._epsilon_buffer.fill(epsilon)
        return self._epsilon_buffer
