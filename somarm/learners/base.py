"""What every learner shares: checks, config helpers, the file format, the abstract verbs.

``LearnerBase`` is the base of every learner kind (checks, memory check, save and load; abstract
``act``, ``learn``, ``predict``); ``somarm.learners.maps.MapLearner`` adds the input map SOM-Q and
the Motoric Map share (and ``greedy_units``); ``ConfigBase`` gives a learner config ``to_dict``,
``from_dict``, ``with_changes`` (typed settings by key, ``somarm.learners.settings``) and
``from_table``. The registry of kinds sits above, in ``somarm.learners``.

A saved learner is one ``.npz`` (written atomically): its arrays, plus a JSON string holding
the kind, config, bounds, seed, trial ids, step count and random-stream positions. Loading it
continues exactly as if the learner had never stopped, even between ``act`` and ``learn``.
"""

from __future__ import annotations

import abc
import dataclasses
import os
from typing import Any, ClassVar

import numpy as np

from somarm.learners import file as learner_file
from somarm.learners.file import restore
from somarm.learners.schedules import Schedule
from somarm.learners.settings import apply_settings, parse_settings
from somarm.learners.som import map_shape
from somarm.streams import PURPOSES, UniformStreams, trial_ids_for
from somarm.validation import check_bounds, check_int, check_memory, check_number, check_periodic, real_array

__all__ = [
    "LearnerBase",
    "ConfigBase",
    "initial_generator",
    "validate_common",
    "config_to_dict",
    "config_from_dict",
]


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
    """What every learner kind shares: checks of its settings, the memory check, save and load.

    A subclass sets ``kind``, ``config_class``, ``_STATE_ARRAYS`` and ``_PENDING_ARRAYS`` (arrays
    saved and restored), says what it has (``has_maps``, ``has_action_map``, ``learned_arrays``),
    and implements ``memory_needed``, ``_build`` (its own tables or maps and random streams),
    ``act``, ``learn`` and ``predict`` (the verbs of ``somarm.protocols.Learner``).
    """

    kind = ""
    config_class: type = object
    #: An input SOM (``input_weights``, ``config.input_shape``) and an action per unit (``action_weights``).
    has_maps: ClassVar[bool] = False
    #: The action units form a map of their own, joined to the input units by a Q-table ``q``
    #: (SOM-Q); False where each input unit keeps a private action (Motoric Map) or there is no map.
    has_action_map: ClassVar[bool] = False
    #: The arrays that show what has been learned, copied for figures mid-run (``run.loop.snapshot``).
    learned_arrays: ClassVar[tuple[str, ...]] = ()
    _STATE_ARRAYS: tuple[str, ...] = ()
    #: What ``act`` leaves for ``learn``: saved too, so a learner saved between them continues.
    _PENDING_ARRAYS: tuple[str, ...] = ()
    #: Arrays a file may lack because it predates them: they keep the value a fresh learner builds.
    _OPTIONAL_ARRAYS: tuple[str, ...] = ()
    #: What to change when the memory check refuses a learner.
    _MEMORY_HINT = "use smaller maps or fewer trials"

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
        check_memory(*self.memory_needed(config, n_trials=self.n_trials, obs_dim=self.obs_dim,
                                         action_dim=self.action_dim), self._MEMORY_HINT)
        self.t = 0
        self._pending = False
        self._current_t = -1
        self._build()

    @classmethod
    @abc.abstractmethod
    def memory_needed(cls, config, *, n_trials: int, obs_dim: int, action_dim: int) -> tuple[str, float]:
        """What a learner of this kind will allocate, ``(description, bytes)``, before it is built.

        The one estimate of a kind's memory: the learner checks it when built, and
        ``somarm.learners.memory_needed`` gives it to whoever plans a run.

        Args:
          config: the kind's config. n_trials: trials. obs_dim, action_dim: the task's dimensions.

        Returns:
          A description of the learner as the user set it (``a somq learner with input_shape=50, ...``)
          and the bytes its arrays take.

        Raises:
          ValueError: settings whose arrays no machine could hold (one line), where a kind has a limit.
        """

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
    def predict(self, observations) -> np.ndarray:
        """Greedy actions, no exploration, no learning: ``(n_trials, [n_obs,] action_dim)``."""

    @property
    def periodic_dimensions(self) -> np.ndarray:
        """The action dimensions this learner wraps round, ``(action_dim,)`` bools (none by default)."""
        return np.zeros(self.action_dim, dtype=np.bool_)

    def _open_streams(self, width: int) -> None:
        self._streams = UniformStreams(self.seed, self.trial_ids, "learner", width)

    # -- checks ---------------------------------------------------------------------------------
    # These run on every step, so they are lean: no copy of an array that is already float64.
    @staticmethod
    def _floats(name: str, value) -> np.ndarray:
        if type(value) is np.ndarray and value.dtype == np.float64:
            return value
        return real_array(name, value)

    def _check_not_pending(self) -> None:
        # A second act() would overwrite the first one's actions before they were learned from.
        if self._pending:
            raise ValueError("act() was called again before learn(): call learn(rewards) for the "
                             "previous actions first (each act() is learned from once)")

    def _current(self) -> dict[str, float]:
        # The schedule values, computed once per step (act and learn share them).
        if self._current_t != self.t:
            self._current_values = {name: getattr(self.config, name).value(self.t)
                                    for name in self.config.SCHEDULES}
            self._current_t = self.t
        return self._current_values

    def parameters(self) -> dict[str, float]:
        """The current value of every schedule (at step ``t``)."""
        return dict(self._current())

    # -- save / load ----------------------------------------------------------------------------
    def _check_restored(self) -> None:
        """Refuse a loaded state whose arrays have the right shapes but values this kind cannot act on
        (indices out of range); ``ValueError`` naming what is wrong. Nothing to check by default."""
        return None

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
