"""Gymnasium environments for the registered one-step tasks: ``somarm/Reach2-v0`` and the rest.

``import somarm.peers.gym`` registers one id per one-step task (``env_id("throw_distance")`` is
``"somarm/ThrowDistance-v0"``), so ``gymnasium.make("somarm/Reach2-v0")`` builds it. Every
episode is one step long: ``reset`` draws the observation, ``step`` throws or reaches and the
episode terminates.

The boundary between Gymnasium's float32 spaces and the tasks' float64 arrays:

- actions live in ``[-1, 1]^action_dim`` (float32) and are mapped to the task's box in float64
  and kept inside it, because float32 rounding can step over a bound (``np.float32(np.pi) >
  np.pi``) and the task rejects any value outside its box;
- observations are the task's float64 observations rounded to float32; rounding is monotonic,
  so they stay inside the float32 observation box. The reward is computed from the float64
  observation, so it equals ``tasks.make``'s for the same observation and action.

Seeding: ``reset(seed=s)`` rebuilds the task with seed ``s``, so episode k after it sees the
observation of trial 0 at step k of ``tasks.make(name, seed=s)``. An environment never seeded
starts from seed 0 (reproducible, like every somarm run).
"""

from __future__ import annotations

from typing import Any

import gymnasium
import numpy as np
from gymnasium import spaces

from somarm import tasks

__all__ = ["OneStepEnv", "env_id", "one_step_tasks", "register", "spaces_for", "to_task_actions"]


def env_id(task: str) -> str:
    """The Gymnasium id of a task: ``"four_goals" -> "somarm/FourGoals-v0"``."""
    return "somarm/" + "".join(part.capitalize() for part in task.split("_")) + "-v0"


def to_task_actions(normalised: Any, low: np.ndarray, high: np.ndarray) -> np.ndarray:
    """Actions in ``[-1, 1]`` mapped linearly onto the task's box ``[low, high]``, float64.

    Args:
      normalised: ``(..., action_dim)``, any float type, every value in [-1, 1].
      low, high: the task's action bounds, ``(action_dim,)`` float64.

    Returns:
      ``(..., action_dim)`` float64, guaranteed inside ``[low, high]`` (the float64 arithmetic
      can land one ulp outside; that is clipped, nothing else is).

    Raises:
      ValueError: NaN, inf or a value outside [-1, 1] (one line).
    """
    a = np.asarray(normalised, dtype=np.float64)
    if a.ndim == 0 or a.shape[-1] != low.size:
        raise ValueError(f"action must have shape (..., {low.size}), got {a.shape}")
    if not np.isfinite(a).all():
        raise ValueError("action must be finite, got NaN or inf")
    if (a < -1.0).any() or (a > 1.0).any():
        raise ValueError(f"action must lie in [-1, 1] (the action space), got values from "
                         f"{a.min():.6g} to {a.max():.6g}")
    return np.clip(low + (a + 1.0) * 0.5 * (high - low), low, high)


def spaces_for(task: Any) -> tuple[spaces.Box, spaces.Box]:
    """The float32 ``(observation_space, action_space)`` of a batched task."""
    observation_space = spaces.Box(task.observation_low.astype(np.float32),
                                   task.observation_high.astype(np.float32), dtype=np.float32)
    action_space = spaces.Box(-1.0, 1.0, shape=(task.action_low.size,), dtype=np.float32)
    return observation_space, action_space


class OneStepEnv(gymnasium.Env):
    """One registered somarm task as a Gymnasium environment with one-step episodes.

    Args:
      task: a registered task name (``somarm tasks`` lists them).
      backend: ``"mujoco"`` (default) or ``"analytic"``.
      **params: the task's parameters (as ``tasks.make``), e.g. ``punish_low=True``.

    Raises:
      ValueError: unknown task, parameter or backend (one line, from ``tasks.make``).
    """

    metadata: dict[str, Any] = {"render_modes": []}

    def __init__(self, task: str = "reach2", *, backend: str = "mujoco", **params: Any):
        if tasks.record(task).episodic:
            raise ValueError(f"{task} has multi-step episodes; somarm.peers.gym adapts the one-step tasks: "
                             f"{', '.join(one_step_tasks())}")
        self.task_name = task
        self._make_kwargs = {"backend": backend, **params}
        self.task = tasks.make(task, seed=0, **self._make_kwargs)
        self.observation_space, self.action_space = spaces_for(self.task)
        self._observation: np.ndarray | None = None

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        """Draw the next observation; ``seed`` restarts the task's stream (see the module doc).

        Returns:
          ``(observation (obs_dim,) float32, {})``.
        """
        super().reset(seed=seed)
        if seed is not None:
            self.task = tasks.make(self.task_name, seed=int(seed), **self._make_kwargs)
        self._observation = self.task.reset()[0]
        return self._observation.astype(np.float32), {}

    def step(self, action):
        """Act once; the episode always terminates.

        Returns:
          ``(observation, reward, terminated=True, truncated=False, {})``; the observation is the
          one the action answered (a one-step episode has no next state).

        Raises:
          ValueError: no ``reset`` before, or an action outside [-1, 1], NaN or inf.
        """
        if self._observation is None:
            raise ValueError(f"{self.task_name}: call reset() before step()")
        actions = to_task_actions(action, self.task.action_low, self.task.action_high)
        if actions.shape != (self.task.action_low.size,):
            raise ValueError(f"action must have shape ({self.task.action_low.size},), got {actions.shape}")
        reward = float(self.task.step(actions[None])[0])
        observation, self._observation = self._observation, None
        return observation.astype(np.float32), reward, True, False, {}


def one_step_tasks() -> list[str]:
    """The registered tasks whose episodes are one step long (the ones adapted here)."""
    return [name for name, record in tasks.records().items() if not record.episodic]


def register() -> None:
    """Register ``somarm/<Name>-v0`` for every one-step task (done on import; again is harmless)."""
    for name in one_step_tasks():
        if env_id(name) not in gymnasium.registry:
            gymnasium.register(env_id(name), entry_point=OneStepEnv, kwargs={"task": name})


register()
