"""Gymnasium environments as batched tasks: any registered id with ``Box`` spaces, named ``gym:ID``.

``tasks.make("gym:Pendulum-v1", n_trials=N, seed=s)`` holds N independent copies of the
environment in Gymnasium's ``SyncVectorEnv``, stepped in lockstep with a batched learner, as every
multi-step task (``somarm.protocols.EpisodicTask``): after ``step``, ``next_observations``,
``terminal`` and ``truncated`` say what happened in each trial, and ``reset()`` starts a new episode
only in the trials whose episode is over. The vector env's autoreset is off (``AutoresetMode.DISABLED``):
``reset()`` resets the trials that are over (``reset_mask``), each with its own seed. Gymnasium's
other modes reset without a seed (``SAME_STEP``, so a trial's episodes would not come from its own
stream) or spend a step on the reset (``NEXT_STEP``, a step the learner would count). Gymnasium's two endings stay apart: ``terminated`` (a state the
future does not follow, such as a fallen pole) is ``terminal``, so the learner does not bootstrap
through it; ``truncated`` (a time limit) is not, so it does, from the true last observation.

Seeding: each episode of trial i resets its copy with a seed drawn from trial i's own stream
(seed, "task", i), so a trial sees the same episodes alone or in a batch, and a run is repeatable.

Scaling (this project's choice, as a user of SB3 would normalise observations): the learner sees
each observation mapped linearly from ``[low, high]`` onto ``[0, 1]`` per dimension, unclipped.
``low`` and ``high`` are the observation ``Box``'s where both are finite; otherwise they are
estimated once, as the 1% and 99% quantiles of observations under uniformly random actions
(widened by a tenth of their range), from a stream of the run's seed. The estimate is a task
parameter (``observation_low``, ``observation_high``), so the run's ``config.json`` keeps it and
a loaded run reuses it. How the bounds are found can be told as data (a learner's preset asks it of
its task: ``somarm.learners.presets.task_params_of``): ``observation_ranges`` (``{"1": [-0.2, 0.2]}``)
takes a dimension's range as given instead of the estimate, and ``observation_widened``
(``{"3": 2.0}``) widens a dimension's range about its middle, so that it counts less in an input
map's distance; both are used up in filling in the bounds, which are what ``config.json`` keeps.
Actions are the action ``Box``'s, in its own units.

Any other ``--task-set KEY=VALUE`` is a keyword argument of ``gymnasium.make`` (``g=5.0`` for
Pendulum, ``max_episode_steps=500``), tried at set-up on one copy of the environment (made, reset and
stepped once with the middle action), so a value the environment cannot take is refused in one line
naming the key, the value and what the environment said, before anything is written. ``nan`` and
``inf`` read as numbers; ``render_mode`` is refused (the copies render nothing: ``somarm view`` draws
an environment's model). Any error of Gymnasium's while making an environment (an unknown or malformed
id, a missing package) is a ``ValueError`` of one line.

Greedy episodes (``run_episodes``) are cut, as a truncation, after ``evaluation_steps`` steps (the
task's own key, default ``EVALUATION_STEPS``) where the environment's time limit is longer or absent,
so an evaluation is bounded whatever ``max_episode_steps`` says; the episodes so cut are counted.
"""

from __future__ import annotations

import contextlib
import copy
import dataclasses
import functools
import json
import math
import warnings
from typing import Any

import numpy as np

from somarm.streams import PURPOSES, trial_generators, trial_ids_for
from somarm.tasks.base import TaskBase
from somarm.tasks.record import TaskRecord
from somarm.validation import check_observation_box

__all__ = ["PREFIX", "DMC_PREFIX", "env_task", "suite_names", "env_id_of", "name_of", "make_env", "BoxScaling", "GymParams", "GymTask", "GymRecord", "record_for", "describe", "BENCHMARKS", "DMC_BENCHMARKS", "EVALUATION_STEPS",
           "estimate_bounds", "scaling_how"]

#: What a Gymnasium task name starts with.
PREFIX = "gym:"
#: What a DeepMind Control Suite task name starts with (``somarm.tasks.dmc``: the suite's tasks as Gymnasium ids).
DMC_PREFIX = "dmc:"
#: The Gymnasium namespace of the suite's tasks (``somarm.tasks.dmc.NAMESPACE``, registered when that module loads).
_DMC_NAMESPACE = "somarm-dmc/"
#: Keys of ``--task-set`` that are the task's own (the rest go to ``gymnasium.make``).
TASK_OWN_KEYS = ("observation_low", "observation_high", "evaluation_steps")
#: Keys that say how the scaling bounds are found (``GymRecord.complete`` uses them up).
SCALING_KEYS = ("observation_ranges", "observation_widened")
#: Texts of ``--task-set`` that read as the float they spell (JSON knows only NaN and Infinity).
_FLOAT_WORDS = ("nan", "inf", "+inf", "-inf", "infinity", "+infinity", "-infinity")
#: Random-action steps behind a bounds estimate, and the quantiles taken.
_ESTIMATE_STEPS = 5000
_QUANTILES = (0.01, 0.99)
#: An observation bound this large counts as none (some environments give +-float32's largest value for
#: an unbounded dimension): scaled from it, every observation would sit at 0.5, so it is estimated.
_UNBOUNDED = 1e6
#: Steps after which a greedy evaluation episode is cut (as a truncation) where the environment's own
#: time limit is longer or absent (``--task-set evaluation_steps=N`` sets another cap): the benchmarks'
#: limits (50 to 1,000 steps) lie within it.
EVALUATION_STEPS = 1000

#: The benchmarks with presets of their own (``somarm.learners.presets``) and default steps; any
#: other id trains with the generic ``gym`` preset for ``_DEFAULT_STEPS`` steps.
BENCHMARKS: dict[str, tuple[str, int]] = {
    "Pendulum-v1": ("pendulum", 500_000),
    "MountainCarContinuous-v0": ("mountaincar", 200_000),
    "InvertedPendulum-v5": ("invertedpendulum", 400_000),
    "Reacher-v5": ("reacher", 200_000),
}
_DEFAULT_STEPS = 100_000

#: The suite tasks with presets of their own and default steps (the report part ``dmc``); any other
#: ``dmc:`` task trains with the generic ``gym`` preset for ``_DEFAULT_STEPS`` steps.
DMC_BENCHMARKS: dict[str, tuple[str, int]] = {
    "dmc:cartpole-balance": ("dmc_balance", 1_000_000),
    "dmc:cartpole-swingup": ("dmc_cartpole", 300_000),
    "dmc:pendulum-swingup": ("dmc_pendulum", 100_000),  # decisions of 5 suite steps (its preset's action_repeat)
    **{name: ("dmc_2d", 100_000) for name in ("dmc:reacher-easy", "dmc:reacher-hard")},
    "dmc:point_mass-easy": ("dmc_point_mass", 600_000),
}

class BoxScaling:
    """``[low, high]`` onto ``[0, 1]`` per dimension and back: how a gym task's observations reach the
    learner, usable without opening an environment."""

    def __init__(self, low: Any, high: Any):
        self.low = np.asarray(low, dtype=np.float64)
        self.high = np.asarray(high, dtype=np.float64)

    def scale(self, observations: Any) -> np.ndarray:
        """Raw observations ``(..., obs_dim)`` onto ``[0, 1]``."""
        return (np.asarray(observations, dtype=np.float64) - self.low) / (self.high - self.low)

    def unscale(self, observations: Any) -> np.ndarray:
        """The inverse of ``scale``."""
        return self.low + np.asarray(observations, dtype=np.float64) * (self.high - self.low)


@dataclasses.dataclass(frozen=True)
class GymParams:
    """A Gymnasium task's parameters: the id, ``gymnasium.make``'s keywords, and the scaling bounds."""

    env_id: str
    kwargs: tuple[tuple[str, Any], ...] = ()  #: keyword arguments of ``gymnasium.make``, sorted by key
    observation_low: tuple[float, ...] | None = None  #: the scaling's low per dimension (None: the Box's)
    observation_high: tuple[float, ...] | None = None  #: the scaling's high per dimension
    evaluation_steps: int | None = None  #: greedy episodes cut after this many steps (None: ``EVALUATION_STEPS``)

    def make_env(self):
        """A new copy of the environment (``gymnasium.make``)."""
        return _make(self.env_id, dict(self.kwargs))


def env_task(name: Any) -> bool:
    """Whether task ``name`` is built on a Gymnasium environment: ``gym:ID`` or ``dmc:DOMAIN-TASK``."""
    return isinstance(name, str) and name.startswith((PREFIX, DMC_PREFIX))


def suite_names() -> tuple[str, ...]:
    """Every DeepMind Control Suite task as ``dmc:DOMAIN-TASK``, in the suite's order (dm_control alone is
    imported: ``somarm tasks`` lists them without Gymnasium)."""
    from dm_control import suite

    return tuple(f"{DMC_PREFIX}{domain}-{task}" for domain, task in suite.ALL_TASKS)


def env_id_of(name: str) -> str:
    """The Gymnasium id behind task ``name``: ``gym:Pendulum-v1`` -> ``Pendulum-v1``, ``dmc:reacher-easy`` ->
    ``somarm-dmc/reacher-easy-v0``.

    Raises:
      ValueError: a ``dmc:`` name of no suite task (one line naming what there is).
    """
    if name.startswith(DMC_PREFIX):
        _gymnasium()
        from somarm.tasks import dmc

        return dmc.gym_id(name)
    return name[len(PREFIX):] if name.startswith(PREFIX) else name


def name_of(env_id: str) -> str:
    """The task name of Gymnasium id ``env_id``: the inverse of ``env_id_of``."""
    if env_id.startswith(_DMC_NAMESPACE) and env_id.endswith("-v0"):
        return DMC_PREFIX + env_id[len(_DMC_NAMESPACE):-len("-v0")]
    return PREFIX + env_id


def make_env(name: str, **kwargs: Any):
    """``gymnasium.make`` of task ``name``'s environment (``gym:ID`` or ``dmc:DOMAIN-TASK``) with ``kwargs``."""
    return _make(env_id_of(name), kwargs)


def _make(env_id: str, kwargs: dict[str, Any]):
    """``gymnasium.make``; this project's own ids (``somarm/Reach2-v0``, the suite's ``somarm-dmc/...``)
    through Gymnasium's ``module:id`` form, which imports the module that registers them first."""
    import gymnasium

    if env_id.startswith("somarm/"):
        env_id = "somarm.peers.gym:" + env_id
    elif env_id.startswith(_DMC_NAMESPACE):
        env_id = "somarm.tasks.dmc:" + env_id
    with warnings.catch_warnings():  # a flat Box is refused in one line (describe), not warned of as well
        warnings.filterwarnings("ignore", message=".*A Box observation space maximum and minimum values are equal")
        return gymnasium.make(env_id, **kwargs)


def _gymnasium():
    try:
        import gymnasium
    except ImportError:
        from somarm.extras import missing

        raise missing("gym", "gym: tasks need gymnasium") from None
    return gymnasium


def _said(exc: BaseException) -> str:
    """What an environment said when it failed: ``TypeError: its message's first line``."""
    return f"{type(exc).__name__}: {(str(exc).strip().splitlines() or [''])[0]}"


def _shown(kwargs: dict[str, Any]) -> str:
    """Keywords as a user gave them: ``g='abc', max_episode_steps=10``."""
    return ", ".join(f"{key}={value!r}" for key, value in kwargs.items())


@functools.lru_cache(maxsize=64)
def describe(env_id: str, kwargs_json: str = "{}") -> dict[str, Any]:
    """The spaces and time limit of environment ``env_id`` made with ``kwargs`` (JSON), read once from
    a copy made, reset and stepped once (the middle action), so that a keyword the environment cannot
    take fails here and not in a run.

    Raises:
      ValueError: an unknown or malformed id, a missing extra (``MissingExtra``), a keyword the
        environment refuses at make, reset or its first step (the key named), non-finite observations
        or rewards, or a space that is not a ``Box`` (one line saying why).
    """
    kwargs = json.loads(kwargs_json)
    try:
        return _describe(env_id, kwargs)
    except _Failed as failed:
        if len(kwargs) > 1:  # name the keyword that fails alone, where one does
            for key, value in kwargs.items():
                try:
                    describe(env_id, json.dumps({key: value}))
                except ValueError as alone:
                    raise alone from None
        raise ValueError(failed.message(name_of(env_id), kwargs)) from None


class _Failed(Exception):
    """The environment failed where it was made, reset or stepped (``describe`` names the keywords)."""

    def __init__(self, when: str, said: str):
        super().__init__(said)
        self.when, self.said = when, said

    def message(self, name: str, kwargs: dict[str, Any]) -> str:
        if not kwargs:
            return f"{name} fails {self.when} ({self.said})"
        keys = " and ".join(kwargs)
        return (f"{name} with keyword{'s' if len(kwargs) > 1 else ''} {_shown(kwargs)} fails {self.when} "
                f"({self.said}); give {keys} a value the environment takes, or leave "
                f"{'them' if len(kwargs) > 1 else 'it'} out")


def _describe(env_id: str, kwargs: dict[str, Any]) -> dict[str, Any]:
    _gymnasium()  # a one-line error where Gymnasium is missing
    from gymnasium import error, spaces

    from somarm.extras import missing

    name = name_of(env_id)
    try:
        env = _make(env_id, kwargs)
    except (error.NameNotFound, error.NamespaceNotFound, error.VersionNotFound, error.UnregisteredEnv) as exc:
        raise ValueError(f"unknown Gymnasium environment {env_id!r} ({exc}); give a registered id, "
                         "such as gym:Pendulum-v1") from None
    except error.DependencyNotInstalled as exc:
        raise missing("gym", f"{name} needs a package that is not installed ({str(exc).splitlines()[0]}); "
                      "the gym extra holds gymnasium's MuJoCo environments") from None
    except error.Error as exc:  # a malformed id, and whatever else Gymnasium refuses at make
        raise ValueError(f"{name} is not an environment Gymnasium can make ({_said(exc)}); give a "
                         "registered id, such as gym:Pendulum-v1") from None
    except TypeError as exc:
        if kwargs:
            raise ValueError(f"{name} does not take these parameters: {exc}") from None
        raise _Failed("when made", _said(exc)) from None
    except ImportError as exc:
        raise missing("gym", f"{name} needs a package that is not installed ({exc}); "
                      "the gym extra holds gymnasium's MuJoCo environments") from None
    except Exception as exc:  # the environment's own check of a keyword's value
        raise _Failed("when made", _said(exc)) from None
    try:
        for what, space in (("observation", env.observation_space), ("action", env.action_space)):
            if not isinstance(space, spaces.Box) or len(space.shape) != 1:
                raise ValueError(f"{name} has a{'n' if what[0] in 'ao' else ''} {what} space "
                                 f"{space}; somarm takes environments whose observation and action "
                                 "spaces are one-dimensional Box spaces")
        action_low = np.asarray(env.action_space.low, dtype=np.float64)
        action_high = np.asarray(env.action_space.high, dtype=np.float64)
        if not (np.isfinite(action_low).all() and np.isfinite(action_high).all()):
            raise ValueError(f"{name} has an unbounded action Box; somarm's action map needs finite bounds")
        _first_step(env, (action_low + action_high) / 2.0)
        observation_low = np.asarray(env.observation_space.low, dtype=np.float64)
        observation_high = np.asarray(env.observation_space.high, dtype=np.float64)
        check_observation_box(name, observation_low, observation_high)
        return {
            "observation_low": np.where(observation_low <= -_UNBOUNDED, -np.inf, observation_low),
            "observation_high": np.where(observation_high >= _UNBOUNDED, np.inf, observation_high),
            "action_low": action_low,
            "action_high": action_high,
            "action_dtype": np.dtype(env.action_space.dtype),
            "max_episode_steps": _episode_steps(env),
            "mujoco": hasattr(env.unwrapped, "model") and type(env.unwrapped.model).__name__ == "MjModel",
        }
    finally:
        with contextlib.suppress(Exception):  # a copy that failed may fail to close as well
            env.close()


def _episode_steps(env) -> int | None:
    """Steps of one whole episode: the TimeLimit's where ``gymnasium.make`` gave one, else the environment's
    own (a suite task ends its episodes itself: ``SuiteEnv.episode_steps``), else None."""
    limit = env.spec.max_episode_steps if env.spec is not None else None
    return limit if limit is not None else getattr(env.unwrapped, "episode_steps", None)


def _first_step(env, action: np.ndarray) -> None:
    """Reset ``env`` and step it once with ``action``; raise ``_Failed`` where it fails or answers with
    a non-finite observation or reward."""
    with warnings.catch_warnings():  # Gymnasium's checker would warn of what is refused here in one line
        warnings.simplefilter("ignore")
        try:
            observation, _ = env.reset(seed=0)
        except Exception as exc:
            raise _Failed("at reset", _said(exc)) from None
        try:
            after, reward, *_ = env.step(action.astype(env.action_space.dtype))
        except Exception as exc:
            raise _Failed("at its first step", _said(exc)) from None
    for when, values in (("at reset", observation), ("at its first step", after)):
        values = np.asarray(values, dtype=np.float64)
        if not np.isfinite(values).all():
            raise _Failed(when, f"its observation {np.array2string(values, precision=3)} is not finite; "
                                "somarm needs finite observations")
    if not np.isfinite(float(reward)):
        raise _Failed("at its first step", f"its reward {float(reward)} is not finite")


def _as_number(value: Any) -> Any:
    """``nan``, ``inf`` and ``-inf`` written as text read as the floats they spell, as ``1e308`` reads as a
    number (JSON spells them only ``NaN`` and ``Infinity``); any other value as it is."""
    if isinstance(value, str) and value.strip().lower() in _FLOAT_WORDS:
        return float(value)
    return value


def box_of(space) -> dict[str, np.ndarray]:
    """An observation Box's bounds as ``describe`` gives them (1e6 or more counts as none)."""
    low, high = np.asarray(space.low, dtype=np.float64), np.asarray(space.high, dtype=np.float64)
    return {"observation_low": np.where(low <= -_UNBOUNDED, -np.inf, low),
            "observation_high": np.where(high >= _UNBOUNDED, np.inf, high)}


def copy_of(env: Any) -> Any:
    """A copy of an environment object with its wrappers (``copy.deepcopy``), for more trials or the
    greedy episodes of a task built on a given environment.

    Raises:
      ValueError: the environment cannot be copied (one line).
    """
    try:
        return copy.deepcopy(env)
    except Exception as exc:
        raise ValueError(f"the environment {env} cannot be copied ({_said(exc)}): give n_trials=1, or its id") from None


def _kwargs_json(params: GymParams) -> str:
    return json.dumps(dict(params.kwargs), sort_keys=True)


def _check_bounds(params: GymParams, size: int) -> None:
    given = [params.observation_low, params.observation_high]
    if (given[0] is None) != (given[1] is None):
        raise ValueError("observation_low and observation_high are given together (both or neither)")
    if given[0] is None:
        return
    low, high = (np.asarray(v, dtype=np.float64) for v in given)
    if low.shape != (size,) or high.shape != (size,):
        raise ValueError(f"observation_low and observation_high of {name_of(params.env_id)} are lists of "
                         f"{size} numbers, got {low.shape[0] if low.ndim else 1} and {high.shape[0] if high.ndim else 1}")
    if not (np.isfinite(low).all() and np.isfinite(high).all() and (high > low).all()):
        raise ValueError("observation_low and observation_high must be finite with high > low in every dimension")


def scaling_how(given: dict[str, Any], size: int, name: str) -> tuple[dict[int, tuple[float, float]], dict[int, float]]:
    """``observation_ranges`` and ``observation_widened`` of ``given`` (JSON objects of dimension ->
    ``[low, high]`` and dimension -> factor) as ``{dimension: (low, high)}`` and ``{dimension: factor}``.

    Raises:
      ValueError: not an object, a dimension outside ``0..size-1``, a range not finite with high > low,
        a factor not finite and > 0 (one line naming the key).
    """
    found: list[dict[int, Any]] = []
    for key, width in (("observation_ranges", 2), ("observation_widened", 1)):
        value = given.get(key) or {}
        what = "[low, high]" if width == 2 else "a factor > 0"
        if not isinstance(value, dict):
            raise ValueError(f"{key} of {name} takes a JSON object of observation dimension -> {what}, got {value!r}")
        out: dict[int, Any] = {}
        for dim, entry in value.items():
            numbers = list(entry) if isinstance(entry, (list, tuple)) else [entry]
            ok = str(dim).isdigit() and int(dim) < size and len(numbers) == width and all(
                isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in numbers)
            if not ok or (numbers[-1] <= numbers[0] if width == 2 else numbers[0] <= 0):
                raise ValueError(f"{key} of {name} takes observation dimensions 0 to {size - 1}, each with {what}, "
                                 f"got {dim!r}: {entry!r}")
            out[int(dim)] = (float(numbers[0]), float(numbers[1])) if width == 2 else float(numbers[0])
        found.append(out)
    return found[0], found[1]


def _told(low: np.ndarray, high: np.ndarray, ranges: dict[int, tuple[float, float]],
          widened: dict[int, float]) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """Bounds with the ranges given put in, then the dimensions widened about their middles."""
    low, high = low.copy(), high.copy()
    for dim, (known_low, known_high) in ranges.items():
        low[dim], high[dim] = known_low, known_high
    for dim, factor in widened.items():
        middle, half = (low[dim] + high[dim]) / 2.0, (high[dim] - low[dim]) / 2.0
        low[dim], high[dim] = middle - factor * half, middle + factor * half
    return tuple(float(v) for v in low), tuple(float(v) for v in high)


def estimate_bounds(params: GymParams, seed: int, *, env: Any = None,
                    how: dict[str, Any] | None = None) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """Scaling bounds where the observation Box is infinite: the 1% and 99% quantiles of
    ``_ESTIMATE_STEPS`` observations under uniformly random actions (episodes reset with seeds of the
    run's "scaling" stream), widened by a tenth of their range; the Box's own bound where it is finite.
    ``how`` (``observation_ranges``, ``observation_widened``; ``scaling_how``) then puts in the ranges
    given and widens the dimensions named. With ``env`` (an environment object, wrapped after
    ``gymnasium.make``), a copy of it is stepped and its own observation Box taken instead."""
    facts = describe(params.env_id, _kwargs_json(params))
    ranges, widened = scaling_how(how or {}, facts["observation_low"].size, name_of(params.env_id))
    rng = np.random.Generator(np.random.PCG64(np.random.SeedSequence(int(seed), spawn_key=(PURPOSES["scaling"],))))
    if env is not None:
        facts = {**facts, **box_of(env.observation_space)}
    env = params.make_env() if env is None else copy_of(env)
    seen = []
    try:
        observation, _ = env.reset(seed=int(rng.integers(2**31)))
        for _ in range(_ESTIMATE_STEPS):
            seen.append(np.asarray(observation, dtype=np.float64))
            action = facts["action_low"] + (facts["action_high"] - facts["action_low"]) * rng.random(facts["action_low"].size)
            observation, _, terminated, truncated, _ = env.step(action.astype(env.action_space.dtype))
            if terminated or truncated:
                observation, _ = env.reset(seed=int(rng.integers(2**31)))
    finally:
        env.close()
    seen = np.array(seen)
    if not np.isfinite(seen).all():
        unbounded = [int(k) for k in np.flatnonzero(~np.isfinite(facts["observation_low"])
                                                    | ~np.isfinite(facts["observation_high"]))]
        bad = [int(k) for k in np.flatnonzero(~np.isfinite(seen).all(axis=0))]
        raise ValueError(f"{name_of(params.env_id)}'s observation Box is infinite in dimension(s) {unbounded}, so "
                         "somarm estimates its scaling from observations under random actions, but the "
                         f"environment gave non-finite observations (nan or inf) in dimension(s) {bad}; give "
                         "observation_low and observation_high")
    low_q, high_q = np.quantile(seen, _QUANTILES, axis=0)
    margin = 0.1 * np.maximum(high_q - low_q, 1e-3)
    box_low, box_high = facts["observation_low"], facts["observation_high"]
    low = np.where(np.isfinite(box_low), box_low, low_q - margin)
    high = np.where(np.isfinite(box_high), box_high, high_q + margin)
    return _told(low, high, ranges, widened)


def _vector(envs: list[Any]):
    """``envs`` as one ``SyncVectorEnv`` whose autoreset is off (``GymTask.reset`` resets, with seeds)."""
    from gymnasium.vector import AutoresetMode, SyncVectorEnv

    return SyncVectorEnv([functools.partial(lambda env: env, env) for env in envs], copy=False,
                         autoreset_mode=AutoresetMode.DISABLED)


class GymTask(TaskBase):
    """N copies of a Gymnasium environment as a batched multi-step task (``EpisodicTask``).

    Args:
      params: a ``GymParams`` with its scaling bounds (``GymRecord.complete`` fills them in).
      n_trials, seed, trial_ids: as every batched task (trial i is the same alone or batched).
      backend: only "gymnasium" (the environment's own ``step``).
      env: an environment object to train in as given, wrappers and all (``SOMQ`` given one): trial 0
        steps it, the other trials and the greedy episodes step copies of it (``copy_of``). Its
        spaces' shapes and action bounds are those of ``gymnasium.make`` of its id.
    """

    episodic = True

    def __init__(self, params: GymParams, *, n_trials: int = 1, seed: int = 0,
                 trial_ids: np.ndarray | None = None, backend: str = "gymnasium", env: Any = None):
        if backend != "gymnasium":
            raise ValueError(f"{name_of(params.env_id)} runs in gymnasium (its own step), got backend {backend!r}")
        facts = describe(params.env_id, _kwargs_json(params))
        self.name = name_of(params.env_id)
        self.params, self.backend, self.seed = params, backend, seed
        self.trial_ids = trial_ids_for(n_trials, trial_ids)
        self.n_trials = int(self.trial_ids.size)
        _check_bounds(params, facts["observation_low"].size)
        if params.observation_low is None:
            if not (np.isfinite(facts["observation_low"]).all() and np.isfinite(facts["observation_high"]).all()):
                raise ValueError(f"{self.name}'s observation Box is unbounded: give observation_low and "
                                 "observation_high (a run estimates them: tasks.record(name).complete)")
            self.scaling = BoxScaling(facts["observation_low"], facts["observation_high"])
        else:
            self.scaling = BoxScaling(params.observation_low, params.observation_high)
        self.observation_low = np.zeros(self.scale_low.size)
        self.observation_high = np.ones(self.scale_low.size)
        self.action_low, self.action_high = facts["action_low"], facts["action_high"]
        self.action_dtype = facts["action_dtype"]
        self.max_episode_steps = facts["max_episode_steps"]
        #: greedy episodes (``run_episodes``) are cut after this many steps where the time limit is longer or absent
        self.evaluation_steps = params.evaluation_steps
        self._generators = trial_generators(seed, self.trial_ids, "task")
        self._given = env
        self._vector = _vector([params.make_env() for _ in range(self.n_trials)] if env is None else
                               [env, *(copy_of(env) for _ in range(self.n_trials - 1))])
        self._eval_envs: list[Any] = []
        self._current = np.zeros((self.n_trials, self.scale_low.size))
        self._over = np.ones(self.n_trials, dtype=bool)
        self._started = False
        self.next_observations = np.zeros_like(self._current)  #: scaled observations after the last step
        self.terminal = np.zeros(self.n_trials, dtype=bool)  #: the last step terminated the episode
        self.truncated = np.zeros(self.n_trials, dtype=bool)  #: the last step hit the time limit
        self.t = 0

    @property
    def scale_low(self) -> np.ndarray:
        """The raw observation that the learner sees as 0."""
        return self.scaling.low

    @property
    def scale_high(self) -> np.ndarray:
        """The raw observation that the learner sees as 1."""
        return self.scaling.high

    def __repr__(self) -> str:
        return f"GymTask({self.params!r}, n_trials={self.n_trials})"

    def _new_env(self):
        """Another copy of the environment: made from its id and keywords, or of the given one."""
        return self.params.make_env() if self._given is None else copy_of(self._given)

    def env_of(self, trial: int):
        """The environment object trial ``trial`` steps."""
        return self._vector.envs[trial]

    def close(self) -> None:
        """Close every copy of the environment (a given environment stays open: it is its owner's)."""
        for env in [*self._vector.envs, *self._eval_envs]:
            if env is not self._given:
                env.close()
        self._vector.closed = True  # its own close would close the given environment too

    # -- the boundary with Gymnasium -------------------------------------------------------
    def scale(self, observations: Any) -> np.ndarray:
        """Raw observations ``(..., obs_dim)`` as the learner sees them: ``[low, high]`` onto ``[0, 1]``."""
        return self.scaling.scale(observations)

    def unscale(self, observations: Any) -> np.ndarray:
        """The inverse of ``scale``: the environment's own observations."""
        return self.scaling.unscale(observations)

    def env_action(self, env, action: np.ndarray) -> np.ndarray:
        """Float64 actions inside the Box as the environment's dtype, kept inside its Box after rounding
        (one action, or a batch of them for the vector env)."""
        space = getattr(env, "single_action_space", env.action_space)
        return np.clip(action.astype(space.dtype), space.low, space.high)

    # -- the BatchedTask protocol ----------------------------------------------------------
    def reset(self) -> np.ndarray:
        """Start new episodes in the trials whose episode is over; every trial's scaled observation."""
        over = self._over.copy()
        if over.any():
            seeds = [int(g.integers(2**31)) if over[i] else None for i, g in enumerate(self._generators)]
            observations, _ = self._vector.reset(seed=seeds, options={"reset_mask": over})
            self._current[over] = self.scale(observations[over])
        self._over[:] = False
        self._started = True
        return self._current.copy()

    def step(self, actions: np.ndarray) -> np.ndarray:
        """Rewards ``(n_trials,)`` for actions ``(n_trials, action_dim)``; sets the episode flags.

        Raises:
          ValueError: no ``reset`` before, or actions of the wrong shape, non-finite or out of bounds.
        """
        if not self._started:
            raise ValueError(f"{self.name}: call reset() before step()")
        actions = self.batch_actions(actions)
        observations, rewards, terminated, truncated, _ = self._vector.step(self.env_action(self._vector, actions))
        self.next_observations[:] = self.scale(observations)
        self.terminal[:], self.truncated[:] = terminated, truncated & ~terminated
        self._current[:] = self.next_observations
        self._over = self.terminal | self.truncated
        self._started = False
        self.t += 1
        return rewards

    def evaluate(self, observations: np.ndarray, actions: np.ndarray) -> np.ndarray:
        """Refused: an environment's state is more than its observation, so one step cannot be
        scored from an observation; a Gymnasium task is scored by whole episodes (``run_episodes``).

        Raises:
          ValueError: always (one line).
        """
        raise ValueError(f"{self.name} is scored by whole episodes (run_episodes), not one step from an observation")

    def sample_observations(self, rng: np.random.Generator, n: int) -> np.ndarray:
        """``n`` scaled first observations ``(n, obs_dim)`` of episodes reset with seeds drawn from ``rng``."""
        env = self._new_env()
        try:
            return np.array([self.scale(env.reset(seed=int(s))[0]) for s in self.sample_starts(rng, n)])
        finally:
            env.close()

    def goal_of(self, observations: np.ndarray) -> np.ndarray:
        """No goal position: ``(..., 0)`` (a Gymnasium environment's goal, if any, is in its observation)."""
        return np.zeros((*np.shape(observations)[:-1], 0))

    def sample_starts(self, rng: np.random.Generator, n: int) -> np.ndarray:
        """``n`` episode starts for ``run_episodes``: the reset seeds, ``(n,)`` integers."""
        return rng.integers(2**31, size=int(n))

    # -- whole episodes ----------------------------------------------------------------------
    def run_episodes(self, policy, starts: np.ndarray, *, paths: bool = False) -> dict[str, np.ndarray]:
        """Whole episodes of ``policy`` (scaled observations ``(m, obs_dim)`` -> actions ``(m, action_dim)``)
        from the reset seeds ``starts`` ``(m,)``, all in lockstep, each to its termination or time limit.

        An episode is cut (as a truncation) after ``evaluation_steps`` steps (default
        ``EVALUATION_STEPS``) where the environment's time limit is longer or absent.

        Returns:
          ``{"length": (m,) steps, "returns": (m,) undiscounted, "terminated": (m,) bools, "cut": (m,)
          bools (the episode was cut at ``evaluation_steps``, before its own end)}``; with
          ``paths`` also ``"path"``: each episode's raw observations, ``(m, longest + 1, obs_dim)``,
          held at the last once the episode is over.
        """
        seeds = np.asarray(starts, dtype=np.int64).reshape(-1)
        m = seeds.size
        while len(self._eval_envs) < m:
            self._eval_envs.append(self._new_env())
        envs = self._eval_envs[:m]
        current = np.array([self.scale(env.reset(seed=int(s))[0]) for env, s in zip(envs, seeds, strict=True)])
        running = np.ones(m, dtype=bool)
        length = np.zeros(m, dtype=np.int64)
        returns = np.zeros(m)
        terminated = np.zeros(m, dtype=bool)
        cap = self.evaluation_steps or EVALUATION_STEPS
        limit = min(self.max_episode_steps or cap, cap)
        cut = np.zeros(m, dtype=bool)
        trace = [self.unscale(current)] if paths else None
        while running.any():
            actions = np.clip(np.asarray(policy(current), dtype=np.float64), self.action_low, self.action_high)
            for i in np.flatnonzero(running):
                observation, reward, term, trunc, _ = envs[i].step(self.env_action(envs[i], actions[i]))
                current[i] = self.scale(observation)
                returns[i] += reward
                length[i] += 1
                terminated[i] = term
                running[i] = not (term or trunc) and length[i] < limit
                cut[i] = not (term or trunc) and length[i] >= limit
            if paths:
                trace.append(self.unscale(current))
        out = {"length": length, "returns": returns, "terminated": terminated, "cut": cut}
        if paths:
            out["path"] = np.stack(trace, axis=1)
        return out


class GymRecord(TaskRecord):
    """The record of one ``gym:ID`` task, made on demand: any keyword goes to ``gymnasium.make``."""

    def params_from(self, given: dict[str, Any]) -> GymParams:
        """The params of ``given`` (``--task-set`` values, typed), tried on one copy of the environment.

        Raises:
          ValueError: ``render_mode``, a bad ``max_episode_steps``, ``evaluation_steps`` or scaling
            bound, or a keyword the environment cannot take (``describe``; one line naming it).
        """
        given = {key: _as_number(value) for key, value in given.items()}
        if "render_mode" in given:
            raise ValueError(f"render_mode={given['render_mode']!r} is not taken by {self.name}: somarm's "
                             "copies of the environment render nothing (somarm view draws its model); leave it out")
        for key in ("max_episode_steps", "evaluation_steps"):
            if key in given:
                value = given[key]
                if isinstance(value, bool) or not isinstance(value, int) or value < 1:
                    raise ValueError(f"{key} of {self.name} takes a whole number of steps >= 1, got {value!r}")
        how = {key: given.pop(key) for key in SCALING_KEYS if key in given}
        own = {key: given.pop(key) for key in TASK_OWN_KEYS if key in given}
        for key in ("observation_low", "observation_high"):
            value = own.get(key)
            if value is not None and (not isinstance(value, (list, tuple)) or not all(
                    isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in value)):
                raise ValueError(f"{key} takes a JSON list of finite numbers, one per observation dimension, got {value!r}")
        bounds = (tuple(own[k]) if own.get(k) is not None else None for k in ("observation_low", "observation_high"))
        params = GymParams(self.params_env_id, tuple(sorted(given.items())), *bounds,
                           evaluation_steps=own.get("evaluation_steps"))
        facts = describe(params.env_id, _kwargs_json(params))
        _check_bounds(params, facts["observation_low"].size)
        scaling_how(how, facts["observation_low"].size, self.name)
        return params

    @property
    def params_env_id(self) -> str:
        return env_id_of(self.name)

    def check_settable(self, given: dict[str, Any]) -> None:
        """Every key is settable: it is a keyword of ``gymnasium.make`` or one of the task's own."""

    def text_fields(self) -> tuple[str, ...]:
        return ()

    def check_values(self, params: dict[str, Any]) -> None:
        """Any JSON value may be a keyword of ``gymnasium.make``; building the params checks them."""
        self.params_from(params)

    def complete(self, params: dict[str, Any], seed: int) -> dict[str, Any]:
        """``params`` with the scaling bounds filled in where the observation Box is unbounded (estimated
        once, from the run's seed: ``estimate_bounds``) or ``observation_ranges`` or ``observation_widened``
        say how to find them (then used up), so the run's ``config.json`` keeps the bounds. Bounds given
        are kept as they are."""
        built = self.params_from(params)
        how = {key: params[key] for key in SCALING_KEYS if key in params}
        rest = {key: value for key, value in params.items() if key not in SCALING_KEYS}
        facts = describe(built.env_id, _kwargs_json(built))
        finite = np.isfinite(facts["observation_low"]).all() and np.isfinite(facts["observation_high"]).all()
        if built.observation_low is not None or (finite and not any(how.values())):
            return rest
        if finite:
            low, high = _told(facts["observation_low"], facts["observation_high"],
                              *scaling_how(how, facts["observation_low"].size, self.name))
        else:
            low, high = estimate_bounds(built, seed, how=how)
        return {**rest, "observation_low": list(low), "observation_high": list(high)}


@functools.lru_cache(maxsize=64)
def record_for(name: str) -> GymRecord:
    """The record of task ``gym:ID`` or ``dmc:DOMAIN-TASK`` (the spaces are read once, by making the environment).

    Raises:
      ValueError: as ``describe``; an unknown suite domain or task (one line naming what there is).
    """
    if name.startswith(PREFIX) and not name[len(PREFIX):]:
        raise ValueError(f"{name!r} names no environment; give gym:ID, such as gym:Pendulum-v1")
    env_id = env_id_of(name)
    facts = describe(env_id)
    preset, n_steps = BENCHMARKS.get(env_id) or DMC_BENCHMARKS.get(name) or ("gym", _DEFAULT_STEPS)
    obs_dim, action_dim = facts["observation_low"].size, facts["action_low"].size
    what = f"dm_control's suite task {name[len(DMC_PREFIX):]}" if name.startswith(DMC_PREFIX) else f"Gymnasium's {env_id}"
    return GymRecord(
        name=name,
        summary=f"{what}: obs {obs_dim} (scaled to [0, 1]), action {action_dim}, multi-step episodes",
        params=GymParams,
        settable=(),
        make=lambda params, **kwargs: GymTask(params, **kwargs),
        environment=_no_dm_env(name),
        preset=preset,
        n_steps=n_steps,
        model="",
        observation_labels=tuple(f"observation {k} (scaled)" for k in range(obs_dim)),
        action_labels=tuple(f"action {k} (normalised)" for k in range(min(action_dim, 2))),
        view="episodes",
        backends=("gymnasium",),
        episodic=True,
    )


def _no_dm_env(name: str):
    def environment(batched):
        if name.startswith(DMC_PREFIX):
            raise ValueError(f"{name} is a suite task already: use dm_control.suite.load, not tasks.load")
        raise ValueError(f"{name} is a Gymnasium environment already: use gymnasium.make, not tasks.load")
    return environment
