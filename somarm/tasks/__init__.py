"""Registered tasks: the reaching arms and the projectile launcher of Smith (2002), and a delayed-reward arm.

Two interfaces to the same tasks:

- ``load(name, seed=0, **params)``: a dm_control ``control.Environment`` (dm_env) whose
  episodes are one step long, as users of ``suite.load`` expect;
- ``make(name, n_trials=1, seed=0, ...)``: a batched task (``somarm.protocols.BatchedTask``)
  for experiments, evaluated in MuJoCo (default) or by the closed forms (``backend="analytic"``).

Episode k of ``load(name, seed=s)`` sees the same observation as trial 0 at step k of
``make(name, seed=s)``. MuJoCo and dm_control load only when a task is built.
"""

from __future__ import annotations

from typing import Any

__all__ = ["names", "describe", "params_type", "load", "make", "set_threads"]

# name -> (one-line description, module of the task, params class name, allowed parameters)
_TASKS: dict[str, tuple[str, str, str, tuple[str, ...]]] = {
    "reach2": ("2-link arm reaches a goal on a circle (Fig. 5); obs goal (x, y), action 2 angles",
               "reach", "ReachParams", ("centre_x", "centre_y", "radius", "dynamics", "settle_time")),
    "reach20": ("20-link arm reaches a goal on a circle (Fig. 11); obs goal (x, y), action 20 angles",
                "reach", "ReachParams", ("centre_x", "centre_y", "radius", "dynamics", "settle_time")),
    "four_goals": ("2-link arm, obs in the unit square, one goal per quadrant, goals move (Fig. 12)",
                   "four_goals", "FourGoalsParams", ("switch_step", "goals_before", "goals_after")),
    "throw": ("throw at target X = 4, a single state (Table 3); action (ux, uy) in [0, 1]^2",
              "throw", "ThrowParams", ("M", "G", "Fr", "W", "X", "punish_low", "tolerance")),
    "throw_distance": ("Table 6 A: target X in [0, 9] observed; action (ux, uy)",
                       "throw", "ThrowParams", ("M", "G", "Fr", "W", "punish_low", "tolerance")),
    "throw_wind": ("Table 6 B: X in [0, 9], wind W in [-3, 0] observed; action (ux, uy)",
                   "throw", "ThrowParams", ("M", "G", "Fr", "punish_low", "tolerance")),
    "throw_friction": ("Table 6 C: X, W, friction Fr in [0, 0.2] observed; action (ux, uy)",
                       "throw", "ThrowParams", ("M", "G", "punish_low", "tolerance")),
    "throw_mass": ("Table 6 D: X, W, Fr, mass M in [1, 2] observed; action (ux, uy)",
                   "throw", "ThrowParams", ("G", "punish_low", "tolerance")),
    "reach2_obstacle": ("actuated 2-link arm steps around a wall to a goal (multi-step, delayed reward); "
                        "obs 2 angles, action 2 target changes",
                        "obstacle", "ObstacleParams",
                        ("max_step", "control_interval", "tolerance", "step_limit", "start_spread")),
}


def names() -> list[str]:
    """Names of the registered tasks."""
    return list(_TASKS)


def _entry(name: str) -> tuple[str, str, str, tuple[str, ...]]:
    if name not in _TASKS:
        raise ValueError(f"unknown task {name!r}; tasks: {', '.join(_TASKS)}")
    return _TASKS[name]


def describe(name: str) -> str:
    """One line describing task ``name``.

    Raises:
      ValueError: unknown name (the names are listed).
    """
    return _entry(name)[0]


def params_type(name: str) -> type:
    """The frozen dataclass holding task ``name``'s parameters."""
    import importlib

    _, module, cls, _ = _entry(name)
    return getattr(importlib.import_module(f"somarm.tasks.{module}"), cls)


def _params(name: str, given: dict[str, Any]):
    allowed = _entry(name)[3]
    unknown = sorted(set(given) - set(allowed))
    if unknown:
        raise ValueError(f"unknown parameter(s) {', '.join(unknown)} for task {name}; "
                         f"its parameters: {', '.join(allowed)}")
    kind = params_type(name)
    try:
        return kind(**given)
    except TypeError as exc:  # pragma: no cover - the allowed names are all fields
        raise ValueError(f"bad parameters for task {name}: {exc}") from None


def make(name: str, *, n_trials: int = 1, seed: int = 0, trial_ids=None, backend: str = "mujoco",
         **params: Any):
    """A batched task (``somarm.protocols.BatchedTask``) for ``n_trials`` independent trials.

    Args:
      name: a registered task (see ``names()``).
      n_trials: independent trials stepped together.
      seed: the run's seed; trial i's observations come from stream (seed, "task", trial id).
      trial_ids: explicit trial indices (e.g. ``[7]`` replays trial 7 alone).
      backend: "mujoco" (default) or "analytic" (closed forms).
      **params: fields of the task's params dataclass (``params_type(name)``).

    Raises:
      ValueError: unknown task, unknown parameter, parameter out of range, unknown backend.
    """
    from somarm.tasks import four_goals, obstacle, reach, throw

    p = _params(name, params)
    kwargs = {"n_trials": n_trials, "seed": seed, "trial_ids": trial_ids, "backend": backend}
    if name in ("reach2", "reach20"):
        return reach.Reach(p, n_links=int(name[5:]), **kwargs)
    if name == "four_goals":
        return four_goals.FourGoals(p, **kwargs)
    if name == "reach2_obstacle":
        return obstacle.Obstacle(p, **kwargs)
    return throw.Throw(p, name=name, **kwargs)


def load(name: str, *, seed: int = 0, **params: Any):
    """A dm_env environment (``dm_control.rl.control.Environment``).

    Episodes are one step long, except ``reach2_obstacle``'s, which end at the goal (discount 0)
    or at the step limit (discount 1).

    Args:
      name: a registered task. seed: the seed of the observations (as trial 0 of ``make``).
      **params: fields of the task's params dataclass.

    Returns:
      A ``control.Environment``; ``reset()`` draws the observation (or start pose), ``step(action)``
      ends a one-step episode.

    Raises:
      ValueError: as for ``make``; actions of the wrong shape, non-finite or out of bounds at ``step``.
    """
    from dm_control.rl import control

    from somarm.tasks import arms, four_goals, launcher, obstacle, reach

    batched = make(name, seed=seed, **params)
    n_sub_steps = 1
    if name in ("reach2", "reach20"):
        physics, task = arms.load_physics(batched.n_links), reach.ReachEnvTask(batched)
        n_sub_steps = batched.settle_steps if batched.actuated else 1
    elif name == "four_goals":
        physics, task = arms.load_physics(2), four_goals.FourGoalsEnvTask(batched)
    elif name == "reach2_obstacle":
        physics, task = obstacle.load_physics(), obstacle.ObstacleEnvTask(batched)
        n_sub_steps = batched.control_steps
    else:
        physics, task = launcher.load_physics(batched.params), launcher.ThrowEnvTask(batched)
    return control.Environment(physics, task, n_sub_steps=n_sub_steps)


def set_threads(n: int) -> None:
    """Threads the MuJoCo backend uses for large batches (default 2, this machine's cores).

    Raises:
      ValueError: ``n`` is not a whole number >= 1.
    """
    from somarm.tasks import arms, flight
    from somarm.validation import check_int

    arms.THREADS = flight.THREADS = check_int("n", n)
