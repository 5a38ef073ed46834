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
    """``(trajectory(ux, uy) -> (n_points, 2), target_of(observation) -> x)`` for a throwing task."""
    from somarm.viewer.shows import load_model

    try:
        from somarm.tasks.throw import simulate_trajectory  # the tasks' own, with their parameters

        params = getattr(task, "params", None)

        def trajectory(ux: float, uy: float) -> np.ndarray:
            return np.asarray(simulate_trajectory(ux, uy, params)[1])
    except ImportError:
        model = load_model("launcher")

        def trajectory(ux: float, uy: float) -> np.ndarray:
            return launcher_flight(model, ux, uy)

    if task_name == "throw":
        return trajectory, lambda observation: _THROW_TARGET_X
    if task is not None and hasattr(task, "target_positions"):
        return trajectory, lambda observation: float(task.target_positions(np.asarray(observation)[None])[0])
    return trajectory, lambda observation: float(np.asarray(observation).ravel()[0])
