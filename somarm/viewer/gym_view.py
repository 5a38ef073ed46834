"""Gymnasium MuJoCo environments (``gym:ID`` tasks) and the suite's tasks (``dmc:DOMAIN-TASK``) in the viewer:
``somarm view gym:ID`` and ``train --view``.

Such a task has no MJCF file of this project's: its model is the environment's own
(``env.unwrapped.model``; a suite task's is its physics' ``MjModel``), drawn by ``somarm.viewer.model_view``. The learner acts on the task's
scaled observations, so the policy here scales each raw observation as the task does and answers
with the greedy action of one trial.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

__all__ = ["environment", "one_step_policy", "view"]


def environment(task_name: str, task_params: dict[str, Any]):
    """A fresh copy of ``task_name``'s environment (``gym:ID`` with its ``gymnasium.make`` keywords, or
    ``dmc:DOMAIN-TASK`` with the suite task's).

    Raises:
      ValueError: not a MuJoCo environment, so there is no model to draw (one line).
    """
    from somarm import tasks
    from somarm.tasks import gym_envs

    params = tasks.record(task_name).params_from(dict(task_params))
    env = params.make_env()
    base = env.unwrapped
    if not (hasattr(base, "model") and hasattr(base, "data")):
        env.close()
        raise ValueError(f"{task_name} is not a MuJoCo environment, so the viewer has no model to draw; it views "
                         f"the MuJoCo ones ({gym_envs.PREFIX}Reacher-v5, {gym_envs.PREFIX}InvertedPendulum-v5, ...)")
    return env


def one_step_policy(task, learner, trial: int = 0) -> Callable[[np.ndarray], np.ndarray]:
    """``policy(observation) -> action`` for one raw observation of ``task``'s environment: the greedy
    action of trial index ``trial`` of ``learner``, on the observation scaled as the task scales it."""

    def policy(observation: np.ndarray) -> np.ndarray:
        scaled = task.scale(np.asarray(observation, dtype=np.float64))
        batch = np.ascontiguousarray(np.broadcast_to(scaled, (learner.n_trials, 1, scaled.size)))
        return np.asarray(learner.predict(batch))[trial, 0].astype(np.float32)

    return policy


def view(task_name: str, *, run=None, trial: int | None = None, task_set: dict[str, Any] | None = None,
         episodes: int = 3, seed: int = 0, html=None, host: str = "127.0.0.1", port: int | None = None,
         log=print):
    """Watch greedy episodes of a trained run on ``task_name`` (random actions without ``run``).

    Args:
      episodes: episodes shown one after another (at most 3,000 states in all).
      trial: the trial id shown (default the run's first).

    Returns:
      What ``model_view.view_states`` returns (the page written, with ``html``).

    Raises:
      ValueError: a run of another task, an unknown trial, or not a MuJoCo environment (one line).
    """
    from somarm import run as runs
    from somarm.viewer.model_view import rollout, view_states

    params = dict(task_set or {})
    policy, lines = None, ["untrained: uniformly random actions"]
    if run is not None:
        config, learner = runs.load(run)
        if config.task != task_name:
            raise ValueError(f"{run} is a run of {config.task}, not of {task_name}")
        ids = learner.trial_ids.tolist()
        shown = ids[0] if trial is None else trial
        if shown not in ids:
            raise ValueError(f"--trial {shown} is not a trial of {run}; its trials: {ids}")
        params = {**config.task_params, **params}
        task = runs.task_for(config, learner)
        policy = one_step_policy(task, learner, ids.index(shown))
        lines = [f"{config.learner} learner ({config.preset}), trial {shown}, seed {config.seed}, "
                 f"{learner.t:,} steps learned; greedy"]
    env = environment(task_name, params)
    try:
        longest = (env.spec.max_episode_steps if env.spec is not None else None) or \
            getattr(env.unwrapped, "episode_steps", None) or 1000
        states = rollout(env, policy, n_steps=min(3000, episodes * longest), seed=seed)
        base = env.unwrapped
        return view_states(base.model, states.qpos, timestep=states.timestep, title=task_name, lines=lines,
                           describe=states.describe, html=html, host=host, port=port, log=log)
    finally:
        env.close()
