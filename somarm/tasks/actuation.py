"""Actuated arms: joint targets in, MuJoCo integrates the position servos, joint states out, batched.

Each arm model (``arm2``, ``arm20``, ``arm2_obstacle``) has one position actuator per hinge; a
target vector is held as the control while MuJoCo integrates ``n_steps`` timesteps from a given
state. Batches go through ``mujoco.rollout``: every trial is its own rollout on a single-arm
model, so trial i's result is the same alone or in a batch of any size, on any number of threads.
"""

from __future__ import annotations

import threading

import mujoco
import numpy as np
from mujoco import rollout

from somarm.tasks.assets import model_path

__all__ = ["Servos", "servos", "steps_of"]

#: Rollouts per call: bounds the memory of the per-step states (chunk x n_steps x state size).
_CHUNK = 256
#: The state layout ``mujoco.rollout`` reads and writes: time, qpos, qvel, act, history, plugin.
_STATE = mujoco.mjtState.mjSTATE_FULLPHYSICS


def steps_of(duration: float, timestep: float) -> int:
    """Whole timesteps in ``duration`` seconds (rounded to the nearest), at least one."""
    return max(1, round(duration / timestep))


class Servos:
    """One arm model whose position actuators track joint targets, for batches of trials.

    Args:
      name: a model of ``assets.MODEL_NAMES`` with one position actuator per joint.
      n_threads: threads ``mujoco.rollout`` shares a batch between (results do not depend on it).
      ctrl_limit: the targets' range +-ctrl_limit (radians) instead of the model's ctrlrange; the joints
        keep their own limits, so a target beyond one drives its joint towards the limit.
    """

    def __init__(self, name: str, *, n_threads: int = 1, ctrl_limit: float | None = None):
        self.model = mujoco.MjModel.from_xml_path(str(model_path(name)))
        if ctrl_limit is not None:
            self.model.actuator_ctrlrange[:] = (-ctrl_limit, ctrl_limit)
        if self.model.nu != self.model.nq or self.model.nq != self.model.nv:
            raise ValueError(f"model {name} needs one position actuator per hinge")  # pragma: no cover
        self.name = name
        self.nq = int(self.model.nq)
        self._datas = [mujoco.MjData(self.model) for _ in range(max(1, int(n_threads)))]
        template = np.empty(mujoco.mj_stateSize(self.model, _STATE))
        mujoco.mj_getState(self.model, self._datas[0], template, _STATE)
        self._template = template
        self._lock = threading.Lock()  # the MjData are scratch space: one batch at a time

    @property
    def timestep(self) -> float:
        return float(self.model.opt.timestep)

    def run(self, qpos: np.ndarray, qvel: np.ndarray, targets: np.ndarray, n_steps: int, *,
            path: bool = False) -> tuple[np.ndarray, np.ndarray]:
        """Hold ``targets`` for ``n_steps`` timesteps starting from ``(qpos, qvel)``.

        Args:
          qpos, qvel: start states, ``(n, nq)`` each.
          targets: joint targets (the controls), ``(n, nq)``; MuJoCo clamps them to the ctrlrange.
          n_steps: timesteps to integrate (>= 1).
          path: return the joint angles after every timestep instead of the end state.

        Returns:
          ``(qpos, qvel)`` at the end, ``(n, nq)`` each; with ``path`` the angles after every timestep,
          ``(n, n_steps, nq)``, and the velocities at the end.
        """
        qpos = np.asarray(qpos, dtype=np.float64).reshape(-1, self.nq)
        qvel = np.asarray(qvel, dtype=np.float64).reshape(-1, self.nq)
        targets = np.asarray(targets, dtype=np.float64).reshape(-1, self.nq)
        n = len(targets)
        out_q = np.empty((n, n_steps, self.nq) if path else (n, self.nq))
        out_v = np.empty((n, self.nq))
        with self._lock:
            for lo in range(0, n, _CHUNK):
                hi = min(n, lo + _CHUNK)
                start = np.tile(self._template, (hi - lo, 1))
                start[:, 1:1 + self.nq] = qpos[lo:hi]
                start[:, 1 + self.nq:1 + 2 * self.nq] = qvel[lo:hi]
                states, _ = rollout.rollout(self.model, self._datas, start, targets[lo:hi, None, :],
                                            nstep=int(n_steps), persistent_pool=len(self._datas) > 1)
                if path:
                    out_q[lo:hi] = states[:, :, 1:1 + self.nq]
                else:
                    out_q[lo:hi] = states[:, -1, 1:1 + self.nq]
                out_v[lo:hi] = states[:, -1, 1 + self.nq:1 + 2 * self.nq]
        return out_q, out_v


_local = threading.local()


def servos(name: str, n_threads: int = 1, *, ctrl_limit: float | None = None) -> Servos:
    """A cached ``Servos`` of model ``name`` for this thread, thread count and target range (``Servos``)."""
    cache = getattr(_local, "servos", None)
    if cache is None:
        cache = _local.servos = {}
    key = (name, int(n_threads), ctrl_limit)
    if key not in cache:
        cache[key] = Servos(name, n_threads=n_threads, ctrl_limit=ctrl_limit)
    return cache[key]
