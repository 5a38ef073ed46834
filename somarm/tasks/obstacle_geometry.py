"""Where reach2_obstacle's arm is and whether it touches the wall: the geometry both the task
(``somarm.tasks.obstacle``) and its shortest-path search (``somarm.tasks.obstacle_search``) read.
"""

from __future__ import annotations

import threading

import mujoco
import numpy as np

from somarm.tasks import arms
from somarm.tasks.assets import model_path

__all__ = ["fingertips", "touches_wall"]


def fingertips(angles: np.ndarray) -> np.ndarray:
    """Fingertip (x, y) ``(..., 2)`` of joint angles ``(..., 2)``, by MuJoCo (as ``arms.fingertips``)."""
    return arms.fingertips(angles, 2)


_collision = threading.local()


def touches_wall(angles: np.ndarray) -> np.ndarray:
    """Whether a link overlaps the wall at rest at joint angles ``(..., 2)``: bools ``(...)``, by MuJoCo."""
    if not hasattr(_collision, "model"):
        _collision.model = mujoco.MjModel.from_xml_path(str(model_path("arm2_obstacle")))
        _collision.data = mujoco.MjData(_collision.model)
    model, data = _collision.model, _collision.data
    angles = np.asarray(angles, dtype=np.float64)
    flat = angles.reshape(-1, 2)
    out = np.empty(len(flat), dtype=bool)
    for i, pose in enumerate(flat):
        data.qpos[:] = pose
        mujoco.mj_fwdPosition(model, data)
        out[i] = any(data.contact[k].dist < 0 for k in range(data.ncon))
    return out.reshape(angles.shape[:-1])
