"""What every learner shares: checks, config helpers, the file format, the abstract verbs.

``LearnerBase`` is the base of SOM-Q and the Motoric Map (abstract ``act``, ``learn``,
``greedy_units``, ``predict``); ``ConfigBase`` gives a learner config ``to_dict``, ``from_dict``,
``with_changes`` (typed settings by key, ``somarm.learners.settings``) and ``from_table``. The registry of kinds sits above, in ``somarm.learners``.

A saved learner is one ``.npz`` (written atomically): its arrays, plus a JSON string holding
the kind, config, bounds, seed, trial ids, step count and random-stream positions. Loading it
continues exactly as if the learner had never stopped, even between ``act`` and ``learn``.
"""

from __future__ import annotations

import abc
import dataclasses
import os
from typing import Any

import numpy as np

from somarm.learners import file as learner_file
from somarm.learners.file import read_file, restore
from somarm.learners.schedules import Schedule
from somarm.learners.settings import apply_settings, parse_settings
from somarm.learners.som import grid_coordinates, grid_distances, map_shape
from somarm.streams import PURPOSES, UniformStreams, trial_ids_for
from somarm.validation import check_bounds, check_int, check_memory, check_number, check_periodic, real_array

__all__ = [
    "LearnerBase",
    "ConfigBase",
    "initial_generator",
    "memory_needed",
    "read_file",
    "validate_common",
    "config_to_dict",
    "config_from_dict",
]


def memory_needed(kind: str, config: Any, n_trials: int, obs_dim: int, action_dim: int) -> tuple[str, float]:
    """What a learner will allocate: ``(description, bytes)``, e.g. for ``check_memory``.

    Counts the grid-distance matrices (built through a ``(units, units, grid dims)`` difference)
    and, per trial, the weights and Q (SOM-Q) or unit values (Motoric Map).
    """
    maps = [name for name in ("input_shape", "action_shape") if hasattr(config, name)]  # Motoric: input only
    units = [int(np.prod(getattr(config, name))) for name in maps]
    n_s, n_a = units[0], units[-1]
    n_floats = sum(n * n * (len(getattr(config, name)) + 1) for n, name in zip(units, maps, strict=True))
    n_floats += n_trials * (n_s * obs_dim + n_a * action_dim + (n_s * n_a if len(maps) == 2 else n_s))
    shapes = ", ".join(f"{name}={'x'.join(map(str, getattr(config, name)))}" for name in maps)
    return f"a {kind} learner with {shapes} and {n_trials} trial(s)", 8.0 * n_floats


def initial_generator(seed: int, trial_id: int) -> np.random.Generator:
    """The generator for a trial's initial weights: a child of its learner stream's seed.

    Using the child (spawn key ``(learner, trial_id, 0)``) keeps the initial weights independent
    of the per-step rows drawn by ``UniformStreams(seed, ..., "learner")``.
    """
    sequence = np.random.SeedSequence(int(seed), spawn_key=(PURPOSES["learner"], int(trial_id), 0))
    return np.random.Generator(np.random.PCG64(sequence))


# -- configs ------------------------------------------------------------------------------------
#: The schedules that are learning rates (a step of ``rate x (target - value)``).
_RATES = ("alpha", "lambda_s", "lambda_a")


def validate_common(config: Any, *, probabilities: tuple[str, ...] = ()) -> None:
    """Check and normalise a learner config in place (frozen dataclass ``__post_init__``)."""
    set_field = object.__setattr__
    for name in ("input_shape", "action_shape"):
        if hasattr(config, name):
            set_field(config, name, map_shape(name, getattr(config, name)))
    for name in config.SCHEDULES:
        value = getattr(config, name)
        if not isinstance(value, Schedule):
            set_field(config, name, Schedule(check_number(name, value, minimum=0.0)))
        elif name in probabilities and max(value.scale, value.floor) > 1.0:
            raise ValueError(f"{name} must be a probability in [0, 1], got {value!r}")
        elif name in _RATES and max(value.scale, value.floor) > 1.0:
            # A rate above 1 overshoots its target: a SOM unit lands beyond the vector it moves to.
            raise ValueError(f"{name} is a learning rate and must lie in [0, 1], got {value!r}")
    set_field(config, "gamma", check_number("gamma", config.gamma, minimum=0.0, maximum=1.0))
    for name in ("neighbourhood_q", "neighbourhood_values", "epsilon_relative", "periodic_actions"):
        if hasattr(config, name) and not isinstance(getattr(config, name), bool):
            raise ValueError(f"{name} must be True or False, got {getattr(config, name)!r}")
    if config.noise not in ("uniform", "gaussian"):
        raise ValueError(f"noise must be 'uniform' or 'gaussian', got {config.noise!r}")
    if config.input_init is not None:
        low, high = check_bounds("input_init", *np.asarray(config.input_init, dtype=float).reshape(2))
        set_field(config, "input_init", (float(low[0]), float(high[0])))


def config_to_dict(config: Any) -> dict[str, Any]:
    """A learner config as JSON-able values (schedules as their ``to_dict``)."""
    out = {}
    for field in dataclasses.fields(config):
        value = getattr(config, field.name)
        out[field.name] = value.to_dict() if isinstance(value, Schedule) else (
            list(value) if isinstance(value, tuple) else value
        )
    return out


def config_from_dict(cls: type, d: dict[str, Any]) -> Any:
    """Inverse of ``config_to_dict``; ValueError naming an unknown or bad field."""
    names = [field.name for field in dataclasses.fields(cls)]
    unknown = sorted(set(d) - set(names))
    if unknown:
        raise ValueError(f"unknown {cls.__name__} fields {unknown}; allowed: {', '.join(names)}")
    values = {}
    for name, value in d.items():
        try:
            if name in cls.SCHEDULES and isinstance(value, dict):
                value = Schedule.from_dict(value)
            elif isinstance(value, list):
                value = tuple(value)
        except (KeyError, TypeError, ValueError) as exc:
            raise ValueError(f"{cls.__name__} field {name}: {exc}") from None
        values[name] = value
    return cls(**values)


class ConfigBase:
    """What every learner config (a frozen dataclass with a ``SCHEDULES`` tuple) shares."""

    SCHEDULES: tuple[str, ...] = ()

    def to_dict(self) -> dict[str, Any]:
        """JSON-able form; ``from_dict`` gives back an equal config."""
        return config_to_dict(self)

    @classmethod
    def from_dict(cls, d: dict[str, Any]):
        """Inverse of ``to_dict``. Raises ValueError naming a bad or unknown field."""
        return config_from_dict(cls, d)

    def with_changes(self, changes: dict[str, Any]):
        """A copy with typed settings changed by key, e.g. ``{"epsilon": 0.2, "decay": InverseDecay(250.0)}``.

        Keys: ``decay`` (a ``Decay``, for every schedule), ``<param>`` or ``<param>.scale`` (a
        number), ``<param>.floor`` (a number) and ``<param>.decay`` (a ``Decay``) for each schedule,
        and every other field by name (``input_shape=(10, 10)``, ``gamma=0.9``,
        ``neighbourhood_q=False``, ``input_init=None``); see ``somarm.learners.settings``.

        Raises:
          ValueError: one line naming the bad key or value (an unknown key lists the allowed ones).
        """
        return apply_settings(self, changes)

    def with_overrides(self, overrides: dict[str, str]):
        """A copy with text settings (``--set KEY=VALUE``) read by ``parse_settings`` and applied.

        E.g. ``{"decay": "exp:0.9985", "input_shape": "10x10", "neighbourhood_q": "false"}``: the
        text forms of ``with_changes``'s values (a decay ``inv:TAU``, ``exp:C`` or ``const``, a shape
        ``50`` or ``10x10``, a bool ``true|false``, ``input_init`` ``LOW:HIGH`` or ``none``).

        Raises:
          ValueError: one line naming the bad key or value (an unknown key lists the allowed ones).
        """
        return apply_settings(self, parse_settings(type(self), overrides))

    @classmethod
    def from_table(cls, table: Any):
        """This kind's config for a paper table (a ``SOMQConfig`` from ``somarm.learners.presets``).

        The default keeps every field the two configs share; a kind overrides it to map more.
        """
        shared = {field.name for field in dataclasses.fields(cls)} & set(table.to_dict())
        return cls(**{name: getattr(table, name) for name in shared})


class LearnerBase(abc.ABC):
    """What SOM-Q and the Motoric Map share: the input map, checks, parameters, save and load.

    A subclass sets ``kind``, ``config_class``, ``_STATE_ARRAYS`` (arrays saved and restored) and
    implements ``_build`` (its own maps and random streams), ``act``, ``learn``, ``greedy_units``
    and ``predict`` (the verbs of ``somarm.protocols.Learner``).
    """

    kind = ""
    config_class: type = object
    _STATE_ARRAYS: tuple[str, ...] = ()
    _PENDING_ARRAYS = ("_observations", "_winners", "_units", "_actions")
    #: Arrays a file may lack because it predates them: they keep the value a fresh learner builds.
    _OPTIONAL_ARRAYS: tuple[str, ...] = ()

    def __init__(self, config, *, observation_low, observation_high, action_low, action_high,
                 n_trials: int = 1, seed: int = 0, trial_ids=None, action_periodic=None):
        if not isinstance(config, self.config_class):
            raise ValueError(f"config must be a {self.config_class.__name__}, got {type(config).__name__}")
        self.config = config
        self.observation_low, self.observation_high = check_bounds("observation", observation_low,
                                                                   observation_high)
        self.action_low, self.action_high = check_bounds("action", action_low, action_high)
        self.n_trials = check_int("n_trials", n_trials, minimum=1)
        self.seed = check_int("seed", seed, minimum=0)
        self.trial_ids = trial_ids_for(self.n_trials, trial_ids)
        self.obs_dim, self.action_dim = self.observation_low.size, self.action_low.size
        # The task's angles: dimensions whose low and high are one point (used where a config says so).
        self.action_periodic = check_periodic(action_periodic, self.action_dim)
        self._check_sizes()
        self.t = 0
        self.input_grid, self._distances_s = self._grid(config.input_shape)
        self.input_weights = np.empty((self.n_trials, self.input_grid.shape[0], self.obs_dim))
        # What act() leaves for learn(): observations, winners, chosen units, perturbed actions.
        self._observations = np.zeros((self.n_trials, self.obs_dim))
        self._winners = np.zeros(self.n_trials, dtype=np.int64)
        self._units = np.zeros(self.n_trials, dtype=np.int64)
        self._actions = np.zeros((self.n_trials, self.action_dim))
        self._pending = False
        self._no_bootstrap = np.zeros(self.n_trials, dtype=np.bool_)
        self._current_t = -1
        self._epsilon_buffer = np.empty(self.action_dim)
        self._build()

    @abc.abstractmethod
    def _build(self) -> None:
        """Make the learner's own maps, values and random streams (called at the end of ``__init__``)."""

    @abc.abstractmethod
    def act(self, observations) -> np.ndarray:
        """Actions ``(n_trials, action_dim)`` for observations ``(n_trials, obs_dim)``, exploring."""

    @abc.abstractmethod
    def learn(self, rewards, next_observations=None, terminal: bool | np.ndarray = True) -> None:
        """Learn from the rewards ``(n_trials,)`` of the actions of the last ``act``."""

    @abc.abstractmethod
    def greedy_units(self, observations) -> tuple[np.ndarray, np.ndarray]:
        """Winning input unit and greedy action unit of each observation."""

    @abc.abstractmethod
    def predict(self, observations) -> np.ndarray:
        """Greedy actions, no exploration, no learning: ``(n_trials, [n_obs,] action_dim)``."""

    def _check_sizes(self) -> None:
        """Refuse, before allocating, maps that do not fit in memory and an epsilon that overflows."""
        check_memory(*memory_needed(self.kind, self.config, self.n_trials, self.obs_dim, self.action_dim),
                     "use smaller maps or fewer trials")
        largest = max(self.config.epsilon.scale, self.config.epsilon.floor)
        span = np.max(self.action_high - self.action_low) if self.config.epsilon_relative else 1.0
        with np.errstate(over="ignore"):  # a perturbed action: up to a few epsilons from a bound
            if not np.isfinite(largest * span * 4.0 + np.max(np.abs([self.action_low, self.action_high]))):
                raise ValueError(f"epsilon={largest:g} is too large: a perturbed action overflows; "
                                 "give a number of the size of the action range")

    @staticmethod
    def _grid(shape: tuple[int, ...]) -> tuple[np.ndarray, np.ndarray]:
        coordinates = grid_coordinates(shape)
        return coordinates, grid_distances(coordinates)

    def _initial_generators(self) -> list[np.random.Generator]:
        return [initial_generator(self.seed, trial_id) for trial_id in self.trial_ids]

    def _initial_input_weights(self, rng: np.random.Generator) -> np.ndarray:
        low, high = self.observation_low, self.observation_high
        if self.config.input_init is not None:
            low = np.full_like(low, self.config.input_init[0])
            high = np.full_like(high, self.config.input_init[1])
        return low + (high - low) * rng.random((self.input_grid.shape[0], self.obs_dim))

    def _open_streams(self, width: int) -> None:
        self._streams = UniformStreams(self.seed, self.trial_ids, "learner", width)

    # -- checks ---------------------------------------------------------------------------------
    # These run on every step, so they are lean: no copy of an array that is already float64, and
    # (with ``finite=False``) the NaN/inf scan is left to the compiled kernel, which does it
    # before it changes anything.
    @staticmethod
    def _floats(name: str, value) -> np.ndarray:
        if type(value) is np.ndarray and value.dtype == np.float64:
            return value
        return real_array(name, value)

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

    def _check_not_pending(self) -> None:
        # A second act() would overwrite the first one's actions before they were learned from.
        if self._pending:
            raise ValueError("act() was called again before learn(): call learn(rewards) for the "
                             "previous actions first (each act() is learned from once)")

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

    def _current(self) -> dict[str, float]:
        # Seven schedule values, computed once per step (act and learn share them).
        if self._current_t != self.t:
            self._current_values = {name: getattr(self.config, name).value(self.t)
                                    for name in self.config.SCHEDULES}
            self._current_t = self.t
        return self._current_values

    def parameters(self) -> dict[str, float]:
        """The current value of every schedule (at step ``t``)."""
        return dict(self._current())

    # -- save / load ----------------------------------------------------------------------------
    def save(self, path: str | os.PathLike) -> None:
        """Write the whole state (config, maps, values, step, random streams) atomically to ``path``."""
        arrays = {name: getattr(self, name) for name in self._STATE_ARRAYS + self._PENDING_ARRAYS}
        learner_file.write(self, path, arrays)

    @classmethod
    def load(cls, path: str | os.PathLike):
        """Reopen a learner written by ``save``; it continues exactly where it stopped.

        Raises:
          ValueError: the file is missing, unreadable, damaged (one line naming the file and what
            is wrong) or holds another kind of learner.
        """
        return restore(cls, path)
