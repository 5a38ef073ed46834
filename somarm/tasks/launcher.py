"""The launcher model in dm_control: one projectile and its target (physics only; the task is in ``throw``)."""

from __future__ import annotations

import mujoco
import numpy as np
from dm_control import mujoco as dm_mujoco

from somarm.tasks import flight
from somarm.tasks.assets import model_path

__all__ = ["LauncherPhysics", "load_physics", "trajectory"]


class LauncherPhysics(dm_mujoco.Physics):
    """dm_control physics of ``models/launcher.xml`` with noun accessors."""

    def _dofs(self) -> tuple[np.ndarray, np.ndarray]:
        model = self.model
        return (np.array([model.jnt_dofadr[model.name2id("x", "joint")]]),
                np.array([model.jnt_dofadr[model.name2id("height", "joint")]]))

    def set_conditions(self, *, Fr: float, W: float, M: float) -> None:
        """Drag Fr (joint damping and the wind motor's gear), wind W (its control) and mass M."""
        self.named.model.dof_damping["x"] = Fr
        self.named.model.actuator_gear["wind", 0] = -Fr
        self.named.data.ctrl["wind"] = W
        if self.named.model.body_mass["projectile"] != M:
            self.named.model.body_mass["projectile"] = M
            mujoco.mj_setConst(self.model.ptr, self.data.ptr)  # the cached mass must follow

    def set_target(self, X: float) -> None:
        self.named.data.mocap_pos["target", 0] = X

    def launch(self, ux: float, uy: float, *, step: float) -> tuple[np.ndarray, np.ndarray]:
        """Put the projectile at the origin with velocity (ux, uy); returns the launch (qpos, qvel)."""
        self.model.opt.timestep = step
        self.data.time = 0.0
        self.data.qpos[:] = 0.0
        self.data.qvel[:] = 0.0
        self.named.data.qvel["x"] = ux
        self.named.data.qvel["height"] = uy
        return self.data.qpos.copy(), self.data.qvel.copy()

    def fly(self, *, previous=None, history: bool = False):
        """Step until the projectile is back at height 0; see ``flight.fly``."""
        x, z = self._dofs()
        steps = flight.max_steps_for(float(np.max(self.data.qvel[z])) if previous is None else
                                     float(previous[1][z].max()), G=-float(self.model.opt.gravity[2]),
                                     dt=float(self.model.opt.timestep))
        return flight.fly(self.model.ptr, self.data.ptr, x=x, z=z, max_steps=steps, previous=previous,
                          history=history)


def load_physics(G: float = 0.05) -> LauncherPhysics:
    """The launcher physics with gravity ``G`` (Table 3's by default)."""
    physics = LauncherPhysics.from_xml_path(str(model_path("launcher")))
    physics.model.opt.gravity[:] = (0.0, 0.0, -G)
    return physics


def trajectory(ux: float, uy: float, *, G: float, Fr: float, W: float, M: float, X: float,
               step: float) -> tuple[np.ndarray, np.ndarray]:
    """One throw stepped with RK4 step ``step`` until it lands (checked velocities; see
    ``somarm.tasks.throw.simulate_trajectory``).

    Returns:
      ``(times (T,), xy (T, 2))``: time and (x, height) at launch, after every step, and at the
      located landing point (the last row, height 0).
    """
    physics = load_physics(G)
    physics.set_conditions(Fr=Fr, W=W, M=M)
    physics.set_target(X)
    physics.launch(ux, uy, step=step)
    _, times, qpos = physics.fly(history=True)
    x, z = physics._dofs()
    return times, np.stack([qpos[:, x[0]], qpos[:, z[0]]], axis=-1)
