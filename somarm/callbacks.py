"""Stable-Baselines3's callbacks in ``SOMQ.learn``: ``BaseCallback`` subclasses, ``EvalCallback``,
``CheckpointCallback``, ``CallbackList``, a list of them or a plain function, called as SB3's
off-policy learners call them.

The order is SB3's: ``init_callback(model)`` and ``on_training_start(locals, globals)`` once, then
every step ``on_rollout_start()``, ``update_locals(locals)``, ``on_step()`` and ``on_rollout_end()``
(SOM-Q learns after every step, as SAC's default ``train_freq=1``), and ``on_training_end()`` once.
``on_step`` returning False ends ``learn`` after that step, as in SB3. The callbacks' ``locals`` hold
``self`` (the model), ``total_timesteps`` (where ``num_timesteps`` ends), ``callback``, and each step's
``new_obs`` (the environment's own observations), ``actions``, ``rewards``, ``dones`` and ``infos``,
one row per trial (SB3's one per environment). Needs the ``peers`` extra (Stable-Baselines3).
"""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["CallbackHook", "as_callback"]


def as_callback(callback: Any, model: Any):
    """SB3's callback of ``callback`` (a callback, a list of them, or a function ``(locals, globals) ->
    bool``), initialised on ``model``; None for None.

    Raises:
      MissingExtra: Stable-Baselines3 is not installed.
    """
    if callback is None:
        return None
    try:
        from stable_baselines3.common.callbacks import BaseCallback, CallbackList, ConvertCallback
    except ImportError:
        from somarm.extras import missing

        raise missing("peers", "SOMQ.learn's callbacks are Stable-Baselines3's") from None
    if isinstance(callback, list):
        callback = CallbackList(callback)
    if not isinstance(callback, BaseCallback):
        callback = ConvertCallback(callback)
    callback.init_callback(model)
    return callback


class CallbackHook:
    """The training loop's ``on_step`` hook that drives an SB3 callback (see the module's docstring).

    Args:
      callback: an initialised SB3 callback (``as_callback``).
      model: the ``SOMQ`` that learns.
      total_timesteps: the ``num_timesteps`` the call ends at.
    """

    def __init__(self, callback, model, total_timesteps: int) -> None:
        self.callback = callback
        self.model = model
        self.stopped = False  #: a callback's ``on_step`` returned False
        n_trials = model.config.n_trials
        self.locals: dict[str, Any] = {"self": model, "total_timesteps": total_timesteps, "callback": callback,
                                       "infos": [{} for _ in range(n_trials)], "dones": np.zeros(n_trials, bool)}

    def start(self) -> None:
        """``on_training_start``, with the locals and this module's globals."""
        self.callback.on_training_start(self.locals, globals())

    def __call__(self, step: int, observations: np.ndarray, actions: np.ndarray, rewards: np.ndarray) -> None:
        """After each step: the step's locals, then the callback; a False answer ends ``learn``."""
        from somarm.tasks.gym_envs import GymTask

        task = self.model.task
        self.callback.on_rollout_start()
        if isinstance(task, GymTask):  # the environment's own observations, not the learner's [0, 1]
            self.locals["new_obs"] = task.unscale(task.next_observations)
        else:
            self.locals["new_obs"] = task.next_observations if task.episodic else observations
        self.locals["actions"] = actions
        self.locals["rewards"] = rewards
        self.locals["dones"] = (task.terminal | task.truncated) if task.episodic else np.ones(len(rewards), bool)
        self.callback.update_locals(self.locals)
        go_on = self.callback.on_step()
        self.callback.on_rollout_end()
        if not go_on:
            self.stopped = True
            raise KeyboardInterrupt  # the loop stops after this step, as on Ctrl-C

    def end(self) -> None:
        """``on_training_end``."""
        self.callback.on_training_end()
