"""What every task shares: the declared members with their defaults; for the one-step tasks, batched
episodes from per-trial streams, checks and dm_env glue.

``TaskBase`` holds what every batched task declares (``somarm.protocols.BatchedTask``): a step
counter and ``set_step``, whether its episodes last several steps (``episodic``) and whether
servos drive its joints (``actuated``), its dimensions. A one-step task is defined once, by a subclass of ``OneStepTask`` that says how uniforms become
observations and how observations and actions become rewards. The batched interface is that
class itself; the dm_env interface (``OneStepEnvTask``) draws its observations from the same
stream as trial ``trial_id`` of the batch and computes its reward from its own MuJoCo physics.
"""

from __future__ import annotations

from collections import OrderedDict
from typing import Any, ClassVar, Literal

import numpy as np
from dm_control.rl import control
from dm_env import specs

from somarm.streams import UniformStreams, trial_generators, trial_ids_for
from somarm.tasks.record import BACKENDS, OWN_BACKENDS
from somarm.validation import real_array

__all__ = ["Backend", "BACKENDS", "TaskBase", "OneStepTask", "OneStepEnvTask", "check_actions", "step_together"]

Backend = Literal["mujoco", "analytic"]


def check_actions(name: str, actions: object, low: np.ndarray, high: np.ndarray) -> np.ndarray:
    """``actions`` as a float array ``(..., action_dim)``, finite and inside [low, high].

    Out-of-range actions are rejected, not clipped: the learner keeps its actions inside the
    bounds it reads from the task, so anything outside is a caller's mistake.

    Raises:
      ValueError: wrong last axis, NaN or inf, or a value outside the bounds (one line).
    """
    array = real_array(name, actions)
    if array.ndim == 0 or array.shape[-1] != low.size:
        raise ValueError(f"{name} must have shape (..., {low.size}), got {array.shape}")
    if not np.isfinite(array).all():
        raise ValueError(f"{name} must be finite, got NaN or inf")
    if (array < low).any() or (array > high).any():
        raise ValueError(f"{name} must lie inside [{_fmt(low)}, {_fmt(high)}], got values from "
                         f"{_fmt(array.reshape(-1, low.size).min(axis=0))} to "
                         f"{_fmt(array.reshape(-1, low.size).max(axis=0))}")
    return array


def _fmt(values: np.ndarray) -> str:
    return "(" + ", ".join(f"{v:.6g}" for v in values) + ")"


class TaskBase:
    """What every batched task declares, with the defaults of a one-step task (``BatchedTask``).

    A subclass sets ``name``, ``n_trials``, the bounds and ``t``, and says where it differs from
    the defaults: ``episodic`` (multi-step episodes: it is then an ``EpisodicTask``), ``actuated``
    (servo-driven joints), ``action_periodic`` (angles over one full turn).
    """

    name: str
    n_trials: int
    observation_low: np.ndarray
    observation_high: np.ndarray
    action_low: np.ndarray
    action_high: np.ndarray
    t: int  #: steps taken (the learner's t)
    #: Episodes last several steps: ``step`` sets ``next_observations``, ``terminal`` and ``truncated``.
    episodic: ClassVar[bool] = False
    #: The joints are servo-driven: an action is a target they track over time.
    actuated: bool = False
    #: An episodic task that finds the shortest path of an episode by search (``shortest_lengths``).
    has_shortest_paths: ClassVar[bool] = False

    @property
    def observation_dim(self) -> int:
        return int(self.observation_low.size)

    @property
    def action_dim(self) -> int:
        return int(self.action_low.size)

    @property
    def action_periodic(self) -> np.ndarray:
        """Which action dimensions are angles whose low and high are one pose, ``(action_dim,)`` bools.

        None by default; a task whose actions are joint angles over one full turn says so.
        """
        return np.zeros(self.action_dim, dtype=np.bool_)

    def batch_actions(self, actions: object) -> np.ndarray:
        """``actions`` checked as one step of the batch: ``(n_trials, action_dim)``, finite, in the box.

        Raises:
          ValueError: the wrong shape, NaN or inf, or a value outside the bounds (one line).
        """
        actions = check_actions("actions", actions, self.action_low, self.action_high)
        if actions.shape != (self.n_trials, self.action_dim):
            raise ValueError(f"actions must have shape ({self.n_trials}, {self.action_dim}), got {actions.shape}")
        return actions

    def scale(self, observations: object) -> np.ndarray:
        """The environment's own observations as the learner sees them: unchanged here (a Gymnasium
        task maps them onto [0, 1])."""
        return np.asarray(observations, dtype=np.float64)

    #: The dtype of the actions the task's environment takes (a Gymnasium task's is its Box's).
    action_dtype: np.dtype = np.dtype(np.float64)

    def set_step(self, t: int) -> None:
        """Set the step counter (e.g. to a trained learner's t, to evaluate in its phase).

        Raises:
          ValueError: ``t`` is not a whole number >= 0.
        """
        if isinstance(t, bool) or not isinstance(t, (int, np.integer)) or t < 0:
            raise ValueError(f"t must be a whole number >= 0, got {t!r}")
        self.t = int(t)

    def continue_at(self, t: int) -> None:
        """Go on from step ``t``, as a model loaded from its run folder does (``SOMQ.load``): the step
        counter is set, and the task's own random numbers (starts, goals, reset seeds) come from streams
        keyed by ``t`` as well, so a continued run meets new starts instead of replaying those it began
        with. At ``t = 0`` this is ``set_step(0)``.

        Raises:
          ValueError: ``t`` is not a whole number >= 0.
        """
        self.set_step(t)
        if self.t:
            self._restart_streams(self.t)

    def _restart_streams(self, start: int) -> None:
        """Draw the task's random numbers from streams keyed by ``start`` (``continue_at``). Here for the
        multi-step tasks, whose trials reset from generators of their own (``_generators``) when their
        episode is over (``_over``): every trial starts a new episode from the new streams."""
        self._generators = trial_generators(self.seed, self.trial_ids, "task", start=start)
        self._over[:] = True


class OneStepTask(TaskBase):
    """Batched one-step episodes for ``n_trials`` independent trials (``BatchedTask``).

    Subclasses set ``name``, the bounds, ``uniform_width`` and implement ``observations_from``
    and ``rewards``; everything else (streams, counters, checks) lives here.

    Args:
      params: the task's frozen parameters.
      n_trials: independent trials. seed: the run's seed. trial_ids: explicit trial indices
        (trial i sees the same observations alone or in a batch). backend: "mujoco" or "analytic".
    """

    uniform_width: ClassVar[int]  #: uniforms drawn per observation

    def __init__(self, params: Any, *, n_trials: int = 1, seed: int = 0,
                 trial_ids: np.ndarray | None = None, backend: Backend = "mujoco"):
        if backend not in OWN_BACKENDS:
            raise ValueError(f"unknown backend {backend!r}; backends: {', '.join(OWN_BACKENDS)}")
        self.params = params
        self.backend = backend
        self.trial_ids = trial_ids_for(n_trials, trial_ids)
        self.n_trials = int(self.trial_ids.size)
        self.seed = seed
        self._streams = UniformStreams(seed, self.trial_ids, "task", self.uniform_width)
        self._observations: np.ndarray | None = None
        self.t = 0  #: steps taken (the learner's t)

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self.params!r}, n_trials={self.n_trials}, backend={self.backend!r})"

    # -- what a task defines -------------------------------------------------------------
    def observations_from(self, uniforms: np.ndarray) -> np.ndarray:
        """Observations ``(n, obs_dim)`` from rows of uniforms ``(n, uniform_width)``."""
        raise NotImplementedError

    def rewards(self, observations: np.ndarray, actions: np.ndarray) -> np.ndarray:
        """Rewards ``(...)`` for checked ``(..., obs_dim)`` and ``(..., action_dim)`` arrays."""
        raise NotImplementedError

    # -- the BatchedTask protocol --------------------------------------------------------
    def reset(self) -> np.ndarray:
        """Next observation of every trial, shape ``(n_trials, obs_dim)``."""
        self._observations = self.observations_from(self._streams.next())
        return self._observations.copy()

    def _restart_streams(self, start: int) -> None:
        self._streams = UniformStreams(self.seed, self.trial_ids, "task", self.uniform_width, start=start)

    def step(self, actions: np.ndarray) -> np.ndarray:
        """Rewards ``(n_trials,)`` for actions ``(n_trials, action_dim)``; advances ``t``.

        Raises:
          ValueError: no ``reset`` before, or actions of the wrong shape, non-finite or out of bounds.
        """
        observations, actions = self.begin_step(actions)
        rewards = self.rewards(observations, actions)
        self.end_step()
        return rewards

    def begin_step(self, actions: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The checked ``(observations, actions)`` of the step about to be taken (``step`` is
        ``begin_step``, ``rewards``, ``end_step``; ``step_together`` pools the middle part).

        Raises:
          ValueError: as ``step``.
        """
        if self._observations is None:
            raise ValueError(f"{self.name}: call reset() before step()")
        actions = check_actions("actions", actions, self.action_low, self.action_high)
        if actions.shape != (self.n_trials, self.action_dim):
            raise ValueError(f"actions must have shape ({self.n_trials}, {self.action_dim}), got {actions.shape}")
        return self._observations, actions

    def end_step(self) -> None:
        """Close the episode ``begin_step`` opened: one step per episode."""
        self._observations = None
        self.t += 1

    @classmethod
    def rewards_together(cls, tasks: list[OneStepTask], steps: list[tuple[np.ndarray, np.ndarray]]) -> list[np.ndarray]:
        """Rewards of several tasks of this class for their ``(observations, actions)``; a task
        class whose physics can take them in one call overrides this (throws do)."""
        return [task.rewards(o, a) for task, (o, a) in zip(tasks, steps, strict=True)]

    def evaluate(self, observations: np.ndarray, actions: np.ndarray) -> np.ndarray:
        """Rewards ``(...)`` for ``(..., obs_dim)`` observations and ``(..., action_dim)`` actions.

        Pure: no counter moves and nothing is drawn.
        """
        observations = np.asarray(observations, dtype=np.float64)
        if observations.ndim == 0 or observations.shape[-1] != self.observation_dim:
            raise ValueError(f"observations must have shape (..., {self.observation_dim}), "
                             f"got {observations.shape}")
        if not np.isfinite(observations).all():
            raise ValueError("observations must be finite, got NaN or inf")
        actions = check_actions("actions", actions, self.action_low, self.action_high)
        try:
            shape = np.broadcast_shapes(observations.shape[:-1], actions.shape[:-1])
        except ValueError:
            raise ValueError(f"observations {observations.shape} and actions {actions.shape} "
                             "do not broadcast") from None
        observations = np.broadcast_to(observations, (*shape, self.observation_dim))
        actions = np.broadcast_to(actions, (*shape, self.action_dim))
        return self.rewards(observations, actions)

    def sample_observations(self, rng: np.random.Generator, n: int) -> np.ndarray:
        """``n`` fresh observations ``(n, obs_dim)`` drawn with ``rng``."""
        return self.observations_from(rng.random((int(n), self.uniform_width)))


def step_together(tasks: list[OneStepTask], actions: list[np.ndarray]) -> list[np.ndarray]:
    """One step of every task, as each task's own ``step`` gives it, in one physics call where they allow.

    Tasks of one class share the call their class's ``rewards_together`` makes (several throw
    tasks: one batch of flights); a throw lands at the same x in any batch, so the rewards equal
    those of separate steps.

    Args:
      tasks: the tasks, each reset. actions: each task's actions ``(n_trials_i, action_dim_i)``.

    Returns:
      Each task's rewards ``(n_trials_i,)``, in order.
    """
    kind = type(tasks[0])
    pooled = (len(tasks) > 1 and all(type(task) is kind for task in tasks) and issubclass(kind, OneStepTask)
              and kind.step is OneStepTask.step)  # a task with its own step (multi-step episodes) steps alone
    if not pooled:
        return [task.step(a) for task, a in zip(tasks, actions, strict=True)]
    steps = [task.begin_step(a) for task, a in zip(tasks, actions, strict=True)]
    rewards = kind.rewards_together(tasks, steps)
    for task in tasks:
        task.end_step()
    return rewards


class OneStepEnvTask(control.Task):
    """A dm_control ``Task`` running one episode of a ``OneStepTask`` per dm_env episode.

    The observation of episode k is the k-th observation of trial ``trial_id`` of a batch
    with the same seed; the subclass writes it into the physics (goal or target marker,
    launch parameters), applies the action and reads the reward back from the physics.
    """

    sub_steps = 1  #: timesteps per dm_env step (``tasks.load`` reads it); a driven arm integrates more

    def __init__(self, batched: OneStepTask, *, observation_key: str):
        self.batched = batched
        self._key = observation_key
        self._observation = np.zeros(batched.observation_dim)
        self._reward: float | None = None

    def initialize_episode(self, physics) -> None:
        self._observation = self.batched.reset()[0]
        self._reward = None
        self.apply_observation(physics, self._observation)

    def before_step(self, action, physics) -> None:
        action = check_actions("action", action, self.batched.action_low, self.batched.action_high)
        if action.shape != (self.batched.action_dim,):
            raise ValueError(f"action must have shape ({self.batched.action_dim},), got {action.shape}")
        self.apply_action(physics, action)

    def after_step(self, physics) -> None:
        self._reward = float(self.reward_from_physics(physics, self._observation))
        self.batched.t += 1

    def action_spec(self, physics):
        return specs.BoundedArray((self.batched.action_dim,), np.float64, self.batched.action_low,
                                  self.batched.action_high, name="action")

    def observation_spec(self, physics):
        return OrderedDict({self._key: specs.BoundedArray(
            (self.batched.observation_dim,), np.float64, self.batched.observation_low,
            self.batched.observation_high, name=self._key)})

    def get_observation(self, physics):
        return OrderedDict({self._key: self._observation.copy()})

    def get_reward(self, physics) -> float:
        return 0.0 if self._reward is None else self._reward

    def get_termination(self, physics):
        # One-step episodes: the episode ends (terminal, discount 0) right after its only action.
        return None if self._reward is None else 0.0

    # -- what a task's dm_env side defines -----------------------------------------------
    def apply_observation(self, physics, observation: np.ndarray) -> None:
        raise NotImplementedError

    def apply_action(self, physics, action: np.ndarray) -> None:
        raise NotImplementedError

    def reward_from_physics(self, physics, observation: np.ndarray) -> float:
        raise NotImplementedError
