"""Where the tasks keep goals, targets and flights, read in one place for the viewer.

The viewer asks the task when it can (``task.goals_for``, ``simulate_trajectory``) and
otherwise falls back on the models' own conventions, documented in their MJCF files: the arm
tasks observe the goal's (x, y); a throw flies in the launcher model's x-z plane.
"""

from __future__ import annotations

from collections.abc import Callable

import mujoco
import numpy as np

__all__ = ["goal_adapter", "throw_adapters", "launcher_flight"]

#: Smith (2002), Fig. 16 and section 5.3: the target of the single-state throw is 4 units away.
_THROW_TARGET_X = 4.0
_MAX_FLIGHT_STEPS = 2000


def goal_adapter(task_name: str, task=None) -> Callable[[np.ndarray], np.ndarray] | None:
    """Observation ``(obs_dim,)`` -> goal (x, y) for the arm tasks; None means "the first two values"."""
    if task is not None and hasattr(task, "goals_for"):  # four_goals: a quadrant's goal, phase by task.t
        return lambda observation: np.asarray(task.goals_for(np.asarray(observation)[None]))[0, :2]
    return None


def launcher_flight(model: mujoco.MjModel, ux: float, uy: float, *, wind: float = 0.0) -> np.ndarray:
    """The flight of one throw in the launcher model, ``(n_points, 2)`` of (x, height), ending on the ground.

    Used when the tasks offer no trajectory function; it steps the same MJCF the tasks use.
    """
    data = mujoco.MjData(model)
    x_adr = model.jnt_qposadr[mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, "x")]
    z_adr = model.jnt_qposadr[mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, "height")]
    data.qvel[model.jnt_dofadr[mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, "x")]] = ux
    data.qvel[model.jnt_dofadr[mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, "height")]] = uy
    if model.nu:
        data.ctrl[:] = wind
    points = [(data.qpos[x_adr], data.qpos[z_adr])]
    for _ in range(_MAX_FLIGHT_STEPS):
        mujoco.mj_step(model, data)
        x, z = data.qpos[x_adr], data.qpos[z_adr]
        if z < 0.0:
            (x0, z0) = points[-1]
            share = z0 / (z0 - z) if z0 != z else 1.0  # cut the last step at the ground
            points.append((x0 + share * (x - x0), 0.0))
            break
        points.append((x, z))
    return np.array(points)


def throw_adapters(task_name: str, task=None):
    """``(trajectory_of(observation), target_of(observation))`` for a throwing task.

    ``trajectory_of(observation)`` is a function ``(ux, uy) -> (n_points, 2)`` of (x, height):
    the flight under that observation's conditions (target, wind, drag, mass), simulated by
    the tasks' ``simulate_trajectory`` when there is a task, else by stepping the launcher model.
    ``target_of(observation)`` is the target's x.
    """
    if task is not None and hasattr(task, "conditions"):
        import dataclasses

        from somarm.tasks.launcher import simulate_trajectory

        def conditions(observation: np.ndarray) -> dict[str, float]:
            values = task.conditions(np.asarray(observation, dtype=np.float64)[None])
            return {k: float(np.ravel(v)[0]) for k, v in values.items()}

        def trajectory_of(observation: np.ndarray):
            params = dataclasses.replace(task.params, **conditions(observation))
            return lambda ux, uy: np.asarray(simulate_trajectory(ux, uy, params)[1])

        return trajectory_of, lambda observation: conditions(observation)["X"]

    from somarm.viewer.shows import load_model

    model = load_model("launcher")

    def fallback_of(observation: np.ndarray):
        return lambda ux, uy: launcher_flight(model, ux, uy)

    if task_name == "throw":
        return fallback_of, lambda observation: _THROW_TARGET_X
    return fallback_of, lambda observation: float(np.asarray(observation).ravel()[0])
