"""How ``SOMQ`` reads the environment it is given: an id, a task name, or an environment object (wrapped
or not), into a task name, ``gymnasium.make``'s keywords and the object to train in as given."""

from __future__ import annotations

import json
from typing import Any

import numpy as np

from somarm.protocols import BatchedTask
from somarm.run import RunConfig

__all__ = ["task_name", "check_fits", "bounds_of", "task_on"]


def task_name(env: Any) -> tuple[str, dict[str, Any], Any]:
    """The task name, Gymnasium keywords and environment object of ``env``: an id, ``gym:ID``, a task name
    (no object), or an environment object (trained in as given: ``GymTask``'s ``env``)."""
    from somarm import tasks
    from somarm.tasks import gym_envs

    if isinstance(env, str):
        if gym_envs.env_task(env) or env in tasks.names():
            return env, {}, None
        return gym_envs.name_of(env), {}, None
    spec = getattr(env, "spec", None)
    if spec is not None and getattr(spec, "id", None):
        # The copies made from the id (somarm evaluate, a model loaded without env) render nothing and
        # keep a time limit set at make.
        kwargs = {k: v for k, v in dict(spec.kwargs or {}).items() if k != "render_mode"}
        from gymnasium import error
        from gymnasium import spec as registered

        try:
            default_limit = registered(spec.id).max_episode_steps
        except error.Error:
            raise ValueError(f"{spec.id} is not a registered Gymnasium environment; SOMQ reads an environment's "
                             "spaces and keywords from the registry (gymnasium.register it, or give a registered "
                             "id)") from None
        if gym_envs.name_of(spec.id).startswith(gym_envs.DMC_PREFIX):  # the registration's own: the suite task
            kwargs = {k: v for k, v in kwargs.items() if k not in ("domain", "task")}
        if spec.max_episode_steps != default_limit:
            kwargs["max_episode_steps"] = spec.max_episode_steps
        check_fits(env, spec.id, kwargs)
        return gym_envs.name_of(spec.id), kwargs, env
    raise ValueError(f"env must be a Gymnasium id (such as 'Pendulum-v1'), a somarm task name or a registered "
                     f"Gymnasium environment, got {type(env).__name__}")


def check_fits(env: Any, env_id: str, kwargs: dict[str, Any]) -> None:
    """Refuse an environment object whose wrappers change what ``gymnasium.make`` of its id gives: the
    observation's shape or the action Box (the learner's action map and a run folder hold those)."""
    from somarm.tasks.gym_envs import describe

    facts = describe(env_id, json.dumps(kwargs, sort_keys=True))
    obs, act = env.observation_space, env.action_space
    if getattr(obs, "shape", None) != facts["observation_low"].shape:
        raise ValueError(f"the wrappers of this {env_id} change its observation shape from "
                         f"{facts['observation_low'].shape} to {getattr(obs, 'shape', None)}; SOMQ takes wrappers "
                         "that keep it (Monitor, TimeLimit, RecordEpisodeStatistics, NormalizeObservation, ...)")
    if not (np.array_equal(np.asarray(getattr(act, "low", np.nan), float), facts["action_low"])
            and np.array_equal(np.asarray(getattr(act, "high", np.nan), float), facts["action_high"])):
        given = [np.asarray(getattr(act, side, np.nan), float).tolist() for side in ("low", "high")]
        raise ValueError(f"the wrappers of this {env_id} change its action Box from "
                         f"[{facts['action_low'].tolist()}, {facts['action_high'].tolist()}] to {given}; SOMQ takes "
                         "wrappers that keep it (its action map spans the environment's own Box)")


def check_preset_view(env: Any, task: str, kwargs: dict[str, Any], preset: str | None) -> None:
    """Refuse, in one line, an environment object made without the keywords its preset sees the task through
    (``dmc_pendulum``'s ``angles`` and ``action_repeat``): the object is trained in as given, so it must be
    made with them."""
    from somarm.learners import presets
    from somarm.tasks import gym_envs

    name = preset or gym_envs.record_for(task).preset
    asked = {k: v for k, v in presets.task_params_of(name, task).items()
             if k not in gym_envs.TASK_OWN_KEYS + gym_envs.SCALING_KEYS}
    differ = {k: v for k, v in asked.items() if json.dumps(kwargs.get(k)) != json.dumps(v)}
    if differ:
        made = ", ".join(f"{k}={json.dumps(v)}" for k, v in asked.items())
        raise ValueError(f"preset {name} sees {task} made with {made}; the environment given was made without "
                         f"{', '.join(differ)}: make it with them (gymnasium.make({env.spec.id!r}, "
                         f"{', '.join(f'{k}={v!r}' for k, v in asked.items())})), give SOMQ its id, or another preset")


def bounds_of(env: Any, task: str, params: dict[str, Any], seed: int) -> dict[str, list[float]]:
    """The scaling bounds of an environment object whose wrappers change its observation Box from its
    id's (NormalizeObservation's is infinite): estimated on a copy of it, so ``config.json`` keeps them;
    none where the Box is its id's."""
    from somarm.learners import presets
    from somarm.tasks import gym_envs

    built = gym_envs.record_for(task).params_from(params)
    facts = gym_envs.describe(built.env_id, json.dumps(dict(built.kwargs), sort_keys=True))
    box = gym_envs.box_of(env.observation_space)
    if all(np.array_equal(box[k], facts[k]) for k in box):
        return {}
    # how the task's preset asks its bounds to be found (its observation ranges, the dimensions widened)
    how = presets.task_params_of(gym_envs.record_for(task).preset, task)
    low, high = gym_envs.estimate_bounds(built, seed, env=env, how=how)
    return {"observation_low": list(low), "observation_high": list(high)}


def task_on(config: RunConfig, env: Any) -> BatchedTask:
    """The task of ``config`` trained in the environment object ``env`` (``GymTask``'s ``env``)."""
    from somarm.tasks import gym_envs

    params = gym_envs.record_for(config.task).params_from(config.task_params)
    return gym_envs.GymTask(params, n_trials=config.n_trials, seed=config.seed, trial_ids=config.trial_ids_array(),
                            env=env)
