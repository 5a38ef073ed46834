"""Where the tasks keep goals, targets and flights, read in one place for the viewer.

The viewer asks the task (``FourGoals.goals_for``, ``Throw.conditions``, ``simulate_trajectory``);
every other arm task observes the goal's (x, y) itself.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable

import numpy as np

__all__ = ["goal_reader", "throw_readers"]


def goal_reader(task) -> Callable[[np.ndarray], np.ndarray] | None:
    """Observation ``(obs_dim,)`` -> goal (x, y) for the arm tasks; None means "the first two values"."""
    from somarm.tasks.four_goals import FourGoals

    if isinstance(task, FourGoals):  # a quadrant's goal, phase by task.t
        return lambda observation: np.asarray(task.goals_for(np.asarray(observation)[None]))[0, :2]
    return None


def throw_readers(task):
    """``(trajectory_of(observation), target_of(observation))`` for a throwing task.

    ``trajectory_of(observation)`` is a function ``(ux, uy) -> (times (T,), xz (T, 2))`` of time
    and (x, height): the flight under that observation's conditions (target, wind, drag, mass),
    simulated by the task's ``simulate_trajectory``, ending at the landing point. ``target_of(observation)`` is the target's x.
    """
    from somarm.tasks.throw import simulate_trajectory

    def conditions(observation: np.ndarray) -> dict[str, float]:
        values = task.conditions(np.asarray(observation, dtype=np.float64)[None])
        return {k: float(np.ravel(v)[0]) for k, v in values.items()}

    def trajectory_of(observation: np.ndarray):
        params = dataclasses.replace(task.params, **conditions(observation))
        return lambda ux, uy: simulate_trajectory(ux, uy, params)

    return trajectory_of, lambda observation: conditions(observation)["X"]
