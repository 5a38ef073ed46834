"""The DeepMind Control Suite as Gymnasium environments: the tasks named ``dmc:DOMAIN-TASK``.

``SuiteEnv("reacher", "easy")`` is one suite task behind Gymnasium's ``Env`` API, so that the batched
Gymnasium task, ``SOMQ`` and Stable-Baselines3 all step the suite's own physics:

- the observation is the suite's observation dict flattened in the suite's key order
  (``observation_keys``), as float64; its Box is unbounded, as the suite's ``Array`` specs are;
- the action Box is the suite's action spec (only tasks whose spec is bounded are offered);
- the suite's time limit ends an episode as a truncation (its discount stays 1, so a learner
  bootstraps through it); an episode the task ends with discount 0 is a termination;
- ``reset(seed=s)`` reseeds the task's own random state (``task.random``) from ``s``, so an episode is
  the one ``suite.load(domain, task, task_kwargs={"random": ...})`` gives for the same draws;
- the keywords are the suite task's own: ``time_limit`` (seconds) and ``random`` (the seed of the
  task's random state before the first seeded reset), and ``action_repeat`` (K, default 1): each action
  is held for K of the suite's control steps and their rewards summed, so a 1,000-step episode is
  ceil(1000 / K) decisions with the same 0-1000 return; the suite's limit ends it, on a shorter last hold;
  and ``angles`` (pairs ``[[c, s], ...]`` of the flattened observation's indices): each pair, an angle's
  cosine and sine as the suite gives orientations, is seen as the angle itself, ``atan2(s, c)`` in
  ``[-pi, pi]``, in the cosine's place (the sine's place is dropped), so that a map over it spreads its
  units evenly round the circle (the pendulum's ``[[0, 1]]``: 0 upright, +-pi hanging down).

Importing this module needs Gymnasium (the ``gym`` extra; dm_control is a core dependency):
``somarm.tasks`` imports it only when a ``dmc:`` task is named.
"""

from __future__ import annotations

import functools
from typing import Any

import gymnasium
import numpy as np
from gymnasium import spaces

__all__ = ["PREFIX", "NAMESPACE", "SuiteEnv", "names", "split_name", "gym_id", "flatten", "observation_keys"]

#: What a suite task's name starts with.
PREFIX = "dmc:"
#: The Gymnasium namespace this module registers the suite's tasks under on import:
#: ``gymnasium.make("somarm-dmc/reacher-easy-v0")``.
NAMESPACE = "somarm-dmc"


@functools.lru_cache(maxsize=1)
def _suite_tasks() -> tuple[tuple[str, str], ...]:
    from dm_control import suite

    return tuple(suite.ALL_TASKS)


def _bounded(spec) -> bool:
    return bool(np.isfinite(spec.minimum).all() and np.isfinite(spec.maximum).all())


def names() -> tuple[str, ...]:
    """Every suite task, as ``dmc:DOMAIN-TASK``, in the suite's order.

    Listed without building them (building all takes seconds): every suite task's action spec is
    bounded (a test opens each), and ``SuiteEnv`` refuses one that is not, should the suite add it.
    ``gym_envs.suite_names`` lists the same without importing Gymnasium (for ``somarm tasks``).
    """
    return tuple(f"{PREFIX}{domain}-{task}" for domain, task in _suite_tasks())


def split_name(name: str) -> tuple[str, str]:
    """``"dmc:point_mass-easy"`` -> ``("point_mass", "easy")``.

    Raises:
      ValueError: no such domain or task in the suite (one line naming what there is).
    """
    body = name[len(PREFIX):] if name.startswith(PREFIX) else name
    domain, _, task = body.partition("-")
    tasks = _suite_tasks()
    domains = sorted({d for d, _ in tasks})
    if domain not in domains:
        raise ValueError(f"unknown dm_control domain {domain!r} in {name!r}; give dmc:DOMAIN-TASK with a "
                         f"domain of {', '.join(domains)}")
    own = [t for d, t in tasks if d == domain]
    if task not in own:
        raise ValueError(f"unknown task {task!r} of dm_control's {domain} in {name!r}; its tasks: {', '.join(own)}")
    return domain, task


def gym_id(name: str) -> str:
    """The Gymnasium id of suite task ``name``: ``"dmc:reacher-easy"`` -> ``"somarm-dmc/reacher-easy-v0"``.

    Raises:
      ValueError: as ``split_name``.
    """
    domain, task = split_name(name)
    return f"{NAMESPACE}/{domain}-{task}-v0"


def observation_keys(observation_spec) -> tuple[tuple[str, int], ...]:
    """``(key, size)`` of each observation in the suite's order (a scalar counts 1)."""
    return tuple((key, int(np.prod(spec.shape, dtype=np.int64))) for key, spec in observation_spec.items())


def flatten(observation) -> np.ndarray:
    """A suite observation dict as one float64 vector, in the dict's (the suite's) key order."""
    return np.concatenate([np.asarray(value, dtype=np.float64).reshape(-1) for value in observation.values()])


def _load(domain: str, task: str, task_kwargs: dict[str, Any]):
    from dm_control import suite

    try:
        return suite.load(domain, task, task_kwargs=task_kwargs)
    except TypeError as exc:
        raise ValueError(f"dm_control's {domain}-{task} does not take these keywords: {exc}") from None


def _check_time_limit(time_limit: Any) -> float | None:
    if time_limit is None:
        return None
    if isinstance(time_limit, bool) or not isinstance(time_limit, (int, float)) or not np.isfinite(time_limit) \
            or time_limit <= 0:
        raise ValueError(f"time_limit takes a finite number of seconds > 0, got {time_limit!r}")
    return float(time_limit)


def _check_action_repeat(action_repeat: Any) -> int:
    if isinstance(action_repeat, bool) or not isinstance(action_repeat, (int, np.integer)) or action_repeat < 1:
        raise ValueError(f"action_repeat takes a whole number of control steps >= 1, got {action_repeat!r}")
    return int(action_repeat)


def _check_angles(angles: Any, size: int) -> tuple[tuple[int, int], ...]:
    """``angles`` as pairs of distinct indices below ``size``, each index in one pair at most (one-line errors)."""
    if angles is None:
        return ()
    allowed = (f"angles takes pairs [[cosine index, sine index], ...] of distinct indices 0 to {size - 1} of the "
               f"flattened observation, each index in one pair at most, got {angles!r}")
    if not isinstance(angles, (list, tuple)):
        raise ValueError(allowed)
    pairs = []
    for pair in angles:
        if not isinstance(pair, (list, tuple)) or len(pair) != 2 or any(
                isinstance(i, bool) or not isinstance(i, (int, np.integer)) or not 0 <= i < size for i in pair):
            raise ValueError(allowed)
        pairs.append((int(pair[0]), int(pair[1])))
    named = [i for pair in pairs for i in pair]
    if len(set(named)) != len(named):
        raise ValueError(allowed)
    return tuple(pairs)


def _check_random(random: Any) -> int | None:
    if random is None:
        return None
    if isinstance(random, bool) or not isinstance(random, (int, np.integer)) or not 0 <= random < 2**32:
        raise ValueError(f"random takes a whole number in [0, 2**32) (the task's seed), got {random!r}")
    return int(random)


class SuiteEnv(gymnasium.Env):
    """One dm_control suite task as a Gymnasium environment (see the module's docstring).

    Args:
      domain, task: a suite task (``dm_control.suite.ALL_TASKS``) with a bounded action spec.
      time_limit: the episode's length in seconds (None: the suite's own for the task).
      random: the seed of the task's random state until the first seeded ``reset``.
      action_repeat: the suite's control steps each action is held for, their rewards summed.
      angles: pairs ``[[c, s], ...]`` of the flattened observation's indices seen as ``atan2(s, c)``.

    Raises:
      ValueError: an unknown domain or task, an unbounded action spec, or a bad keyword (one line).
    """

    metadata = {"render_modes": []}

    def __init__(self, domain: str, task: str, *, time_limit: float | None = None, random: int | None = None,
                 action_repeat: int = 1, angles: Any = None):
        split_name(f"{domain}-{task}")
        self.action_repeat = _check_action_repeat(action_repeat)
        kwargs: dict[str, Any] = {"random": _check_random(random)}
        if (limit := _check_time_limit(time_limit)) is not None:
            kwargs["time_limit"] = limit
        self.domain, self.task = domain, task
        self.environment = _load(domain, task, kwargs)
        action_spec = self.environment.action_spec()
        if not _bounded(action_spec):
            raise ValueError(f"dm_control's {domain}-{task} has an unbounded action spec; somarm's "
                             "action map needs finite bounds")
        self.keys = observation_keys(self.environment.observation_spec())
        size = sum(n for _, n in self.keys)
        self.angles = _check_angles(angles, size)  #: the (cosine, sine) index pairs seen as angles
        self._kept = np.array([i for i in range(size) if i not in {s for _, s in self.angles}], dtype=np.int64)
        low = np.full(size, -np.inf)
        low[[c for c, _ in self.angles]] = -np.pi
        self.observation_space = spaces.Box(low[self._kept], -low[self._kept], (self._kept.size,), np.float64)
        self.action_space = spaces.Box(np.asarray(action_spec.minimum, dtype=np.float64).reshape(-1),
                                       np.asarray(action_spec.maximum, dtype=np.float64).reshape(-1),
                                       dtype=np.float64)
        # control.Environment keeps its step limit (time limit / control timestep) private.
        step_limit = self.environment._step_limit
        #: Steps of one whole episode (the time limit over the control timestep, over ``action_repeat``;
        #: None: no limit).
        self.episode_steps = -(-int(round(step_limit)) // self.action_repeat) if np.isfinite(step_limit) else None

    @property
    def dt(self) -> float:
        """Seconds of one step (the suite's control timestep times ``action_repeat``), as Gymnasium's MuJoCo
        environments have it."""
        return float(self.environment.control_timestep()) * self.action_repeat

    @property
    def physics(self):
        """The suite task's ``dm_control.mujoco.Physics``."""
        return self.environment.physics

    @property
    def model(self):
        """MuJoCo's ``MjModel`` of the task, as Gymnasium's MuJoCo environments have it (the viewer draws it)."""
        return self.environment.physics.model.ptr

    @property
    def data(self):
        """MuJoCo's ``MjData`` of the task, stepped by the suite."""
        return self.environment.physics.data.ptr

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        super().reset(seed=seed)
        if seed is not None:
            self.environment.task.random.seed(int(self.np_random.integers(2**32)))
        step = self.environment.reset()
        return self.observation_of(step.observation), {}

    def observation_of(self, observation) -> np.ndarray:
        """A suite observation dict as this environment shows it: flattened, each ``angles`` pair seen as its angle."""
        flat = flatten(observation)
        for c, s in self.angles:
            flat[c] = np.arctan2(flat[s], flat[c])
        return flat[self._kept] if self.angles else flat

    def step(self, action):
        action = np.asarray(action, dtype=np.float64)
        step = self.environment.step(action)
        reward = float(step.reward or 0.0)
        for _ in range(self.action_repeat - 1):
            if step.last():
                break
            step = self.environment.step(action)
            reward += float(step.reward or 0.0)
        terminated = bool(step.last() and step.discount == 0.0)
        truncated = bool(step.last() and not terminated)
        return self.observation_of(step.observation), reward, terminated, truncated, {}

    def close(self) -> None:
        self.environment.close()


def _register() -> None:
    """Every suite task as a Gymnasium id (``gym_id``); the suite ends its own episodes, so no TimeLimit."""
    for domain, task in _suite_tasks():
        env_id = f"{NAMESPACE}/{domain}-{task}-v0"
        if env_id not in gymnasium.registry:
            gymnasium.register(env_id, entry_point=SuiteEnv, kwargs={"domain": domain, "task": task},
                               disable_env_checker=True)


_register()
