"""A Stable-Baselines3 ``VecEnv`` over one batched task: N trials in one physics call.

SB3 normally steps N copies of an environment one by one (``DummyVecEnv``). Here the N
environments are the N trials of one ``tasks.make(name, n_trials=N)``: one ``step`` is one
batched physics call for all of them, feeding one learner. Spaces, action mapping and rewards
are those of ``somarm.peers.gym`` (float32 spaces, actions in [-1, 1] mapped into the task's box).

Every episode is one step long, so every step ends all N episodes: the returned observations are
the next episodes' (SB3's auto-reset), and ``infos[i]["terminal_observation"]`` holds the
observation trial i's action answered.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from stable_baselines3.common.vec_env import VecEnv

from somarm import tasks
from somarm.peers.gym import spaces_for, to_task_actions
from somarm.validation import check_int

__all__ = ["BatchedVecEnv"]


class BatchedVecEnv(VecEnv):
    """``n_envs`` trials of one somarm task as an SB3 vectorised environment.

    Seeding: ``seed(s)`` (or ``seed=s`` here) makes env i draw the observations of trial i of
    ``tasks.make(name, n_trials=n_envs, seed=s)`` from the next ``reset`` on (not SB3's usual
    ``s + i`` per env: the task already gives each trial its own stream).

    Args:
      task: a registered task name.
      n_envs: trials stepped together (>= 1).
      seed: the task's seed (default 0).
      backend: ``"mujoco"`` (default) or ``"analytic"``.
      **params: the task's parameters (as ``tasks.make``).

    Raises:
      ValueError: bad ``n_envs``, unknown task, parameter or backend (one line).
    """

    render_mode = None  #: nothing renders here; the meshcat viewer is ``somarm view``

    def __init__(self, task: str, n_envs: int = 1, *, seed: int = 0, backend: str = "mujoco", **params: Any):
        if tasks.record(task).episodic:
            raise ValueError(f"{task} has multi-step episodes; BatchedVecEnv steps one-step tasks")
        self.task_name = task
        self._make_kwargs = {"n_trials": check_int("n_envs", n_envs), "backend": backend, **params}
        self.task = tasks.make(task, seed=seed, **self._make_kwargs)
        observation_space, action_space = spaces_for(self.task)
        super().__init__(n_envs, observation_space, action_space)
        self._observations: np.ndarray | None = None
        self._actions: np.ndarray | None = None
        self._dones = np.ones(n_envs, dtype=bool)

    def reset(self) -> np.ndarray:
        """Observations ``(n_envs, obs_dim)`` float32 of the next episodes (a new seed applies first)."""
        if self._seeds[0] is not None:
            self.task = tasks.make(self.task_name, seed=int(self._seeds[0]), **self._make_kwargs)
        self._reset_seeds()
        self._reset_options()
        self._observations = self.task.reset()
        return self._observations.astype(np.float32)

    def step_async(self, actions: np.ndarray) -> None:
        self._actions = actions

    def step_wait(self):
        """One batched physics call: ``(next observations, rewards, dones, infos)``."""
        if self._observations is None or self._actions is None:
            raise ValueError(f"{self.task_name}: call reset() and step_async() before step_wait()")
        actions = to_task_actions(np.reshape(self._actions, (self.num_envs, -1)), self.task.action_low,
                                  self.task.action_high)
        rewards = self.task.step(actions).astype(np.float32)
        terminal = self._observations.astype(np.float32)
        self._observations = self.task.reset()
        self._actions = None
        # SB3's off-policy buffers read the answered observation from here when an episode ends.
        infos = [{"terminal_observation": row} for row in terminal]
        return self._observations.astype(np.float32), rewards, self._dones.copy(), infos

    def close(self) -> None:
        """Nothing to release: the task holds no process or file."""

    def get_attr(self, attr_name: str, indices=None) -> list[Any]:
        """The attribute of this adapter (all envs share it), once per index."""
        return [getattr(self, attr_name) for _ in self._get_indices(indices)]

    def set_attr(self, attr_name: str, value: Any, indices=None) -> None:
        """Set an attribute shared by all envs."""
        setattr(self, attr_name, value)

    def env_method(self, method_name: str, *method_args, indices=None, **method_kwargs) -> list[Any]:
        """Call a method of the batched task once per index."""
        method = getattr(self.task, method_name)
        return [method(*method_args, **method_kwargs) for _ in self._get_indices(indices)]

    def env_is_wrapped(self, wrapper_class, indices=None) -> list[bool]:
        """No env is wrapped: they are trials of one task, not Gymnasium envs."""
        return [False for _ in self._get_indices(indices)]
