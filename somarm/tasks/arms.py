"""The planar arms in MuJoCo: kinematic setpoints in, fingertip positions out, batched.

A reach action is a set of joint angles to move *to* (Fig. 6), so no dynamics are needed:
write qpos, run ``mj_kinematics``, read the ``fingertip`` site. Batches are evaluated on one
model holding many copies of the arm (built from the arm's own MJCF, as many as the batch needs up
to a most), chunk by chunk, and large batches are shared between threads (MuJoCo releases the GIL).
"""

from __future__ import annotations

import threading

import mujoco
import numpy as np
from dm_control import mujoco as dm_mujoco

from somarm.tasks.assets import ARM20_LINK_LENGTH, model_path
from somarm.tasks.pool import shared_pool, threads_here

__all__ = ["LINK_LENGTHS", "TIMESTEP", "ArmPhysics", "ArmBatch", "fingertips"]

#: This project's link lengths (the paper gives none): 0.4 + 0.4, and 20 links of 0.05.
LINK_LENGTHS: dict[int, np.ndarray] = {2: np.array([0.4, 0.4]), 20: np.full(20, ARM20_LINK_LENGTH)}
_MODELS = {2: "arm2", 20: "arm20"}
#: The arm models' timestep (s): the unit of the actuated tasks' settle time and control interval.
TIMESTEP = 0.01
#: Most arms per batch model: enough to hide Python's per-call cost (the 20-link arm needs fewer).
_COPIES = {2: 128, 20: 32}
#: Arms per batch model below the most: a batch runs in the smallest of these that holds it, so a
#: training step of 5 or 20 arms computes 5 or 20, not a full model's (few models built).
_SIZES = (*range(1, 9), 12, 16, 20, 24, 32, 48, 64, 96, 128)
#: Threads for batches of more than 512 arms (2 by default: a small machine); see ``tasks.set_threads``.
THREADS = 2


def _check_links(n_links: int) -> str:
    if n_links not in _MODELS:
        raise ValueError(f"n_links must be one of {', '.join(map(str, _MODELS))}, got {n_links!r}")
    return _MODELS[n_links]


class ArmPhysics(dm_mujoco.Physics):
    """dm_control physics of one arm with noun accessors, as in dm_control's reacher."""

    def set_angles(self, angles: np.ndarray) -> None:
        """Move the arm to the joint angles (a kinematic setpoint) and update the kinematics."""
        self.data.qpos[:] = angles
        self.data.qvel[:] = 0.0
        mujoco.mj_kinematics(self.model.ptr, self.data.ptr)

    def set_targets(self, targets: np.ndarray) -> None:
        """Hand joint targets to the position servos (the controls); the next steps track them."""
        self.data.ctrl[:] = targets

    def angles(self) -> np.ndarray:
        """The joint angles, ``(nq,)``."""
        return self.data.qpos.copy()

    def fingertip(self) -> np.ndarray:
        """(x, y) of the fingertip site."""
        return self.named.data.site_xpos["fingertip", :2].copy()

    def goal(self) -> np.ndarray:
        """(x, y) of the goal marker."""
        return self.named.data.mocap_pos["goal", :2].copy()

    def set_goal(self, xy: np.ndarray) -> None:
        self.named.data.mocap_pos["goal", :2] = xy

    def fingertip_to_goal(self) -> float:
        """Distance from the fingertip to the goal marker."""
        return float(np.linalg.norm(self.fingertip() - self.goal()))


def load_physics(n_links: int) -> ArmPhysics:
    """The dm_control physics of ``models/arm2.xml`` or ``models/arm20.xml``."""
    return ArmPhysics.from_xml_path(str(model_path(_check_links(n_links))))


class ArmBatch:
    """``copies`` arms of ``n_links`` links in one MuJoCo model, for batched fingertips.

    The model attaches ``copies`` copies of the arm's first link (and so the whole chain) from
    the arm's MJCF; the floor, base and goal marker are left out.
    """

    def __init__(self, n_links: int, copies: int | None = None):
        copies = copies or _COPIES[n_links]
        path = str(model_path(_check_links(n_links)))
        spec = mujoco.MjSpec.from_file(path)
        for i in range(copies):
            arm = mujoco.MjSpec.from_file(path)
            spec.worldbody.add_frame().attach_body(arm.body("link1"), f"copy{i}_", "")
        # The original arm and goal stay in the model (they are cheap); copies are addressed by name.
        self.model = spec.compile()
        self.data = mujoco.MjData(self.model)
        self.n_links, self.copies = n_links, copies
        joints = [self.model.joint(f"copy{i}_theta{j + 1}").id for i in range(copies) for j in range(n_links)]
        self._qpos = np.array([self.model.jnt_qposadr[j] for j in joints])
        self._sites = np.array([self.model.site(f"copy{i}_fingertip").id for i in range(copies)])
        if not np.array_equal(self._qpos, np.arange(self._qpos[0], self._qpos[0] + copies * n_links)):
            raise RuntimeError("arm copies' joints are not contiguous in qpos")  # pragma: no cover
        self._start = int(self._qpos[0])

    def fingertips(self, angles: np.ndarray, out: np.ndarray) -> None:
        """Fingertips of ``angles (m, n_links)`` into ``out (m, 2)``, chunk by chunk."""
        qpos = self.data.qpos
        start, stop_all = self._start, self._start + self.copies * self.n_links
        for lo in range(0, len(angles), self.copies):
            chunk = angles[lo:lo + self.copies]
            m = len(chunk)
            qpos[start:stop_all][: m * self.n_links] = chunk.ravel()
            mujoco.mj_kinematics(self.model, self.data)
            out[lo:lo + m] = self.data.site_xpos[self._sites[:m], :2]


_local = threading.local()


def _batch(n_links: int, m: int) -> ArmBatch:
    """This thread's model for a batch of ``m`` arms: the smallest size that holds them, at most ``_COPIES``."""
    copies = min([s for s in _SIZES if s >= m] + [_COPIES[n_links]])
    cache = getattr(_local, "arms", None)
    if cache is None:
        cache = _local.arms = {}
    if (n_links, copies) not in cache:
        cache[(n_links, copies)] = ArmBatch(n_links, copies)
    return cache[(n_links, copies)]


def fingertips(angles: np.ndarray, n_links: int, *, n_threads: int | None = None) -> np.ndarray:
    """Fingertip positions of arms at the given joint angles, computed by MuJoCo.

    Args:
      angles: joint angles in radians, shape ``(..., n_links)`` (not checked against bounds).
      n_links: 2 or 20 (the models ``arm2`` and ``arm20``).
      n_threads: threads for batches of more than 512 arms (default ``THREADS``).

    Returns:
      Array ``(..., 2)`` of fingertip (x, y).

    Raises:
      ValueError: unknown ``n_links`` or angles whose last axis is not ``n_links``.
    """
    _check_links(n_links)
    angles = np.asarray(angles, dtype=np.float64)
    if angles.ndim == 0 or angles.shape[-1] != n_links:
        raise ValueError(f"angles must have shape (..., {n_links}), got {angles.shape}")
    flat = np.ascontiguousarray(angles.reshape(-1, n_links))
    out = np.empty((len(flat), 2))
    workers = (threads_here(THREADS) if n_threads is None else n_threads) if len(flat) > 512 else 1
    if workers <= 1:
        _batch(n_links, len(flat)).fingertips(flat, out)
    else:
        pool = shared_pool(workers)
        bounds = np.linspace(0, len(flat), workers + 1).astype(int)
        futures = [pool.submit(lambda a, b: _batch(n_links, b - a).fingertips(flat[a:b], out[a:b]), a, b)
                   for a, b in zip(bounds[:-1], bounds[1:], strict=True)]
        for future in futures:
            future.result()
    return out.reshape(*angles.shape[:-1], 2)
