"""The launcher model in dm_control: one projectile and its target (physics only; the task is in ``throw``)."""

from __future__ import annotations

import numpy as np
from dm_control import mujoco as dm_mujoco

from somarm.tasks import flight
from somarm.tasks.assets import model_path

__all__ = ["LauncherPhysics", "load_physics", "trajectory"]


class LauncherPhysics(dm_mujoco.Physics):
    """dm_control physics of ``models/launcher.xml`` with noun accessors."""

    def _dofs(self) -> tuple[np.ndarray, np.ndarray]:
        """dof addresses of the slide joints ``x`` and ``height``, each of shape ``(1,)``."""
        cached = getattr(self, "_dof_cache", None)
        if cached is None or cached[0] is not self.model.ptr:
            model = self.model
            cached = self._dof_cache = (model.ptr, np.array([model.jnt_dofadr[model.name2id("x", "joint")]]),
                                        np.array([model.jnt_dofadr[model.name2id("height", "joint")]]))
        return cached[1], cached[2]

    def set_conditions(self, *, Fr: float, W: float, M: float) -> None:
        """Drag Fr, wind W (the wind motor's control) and mass M of the next launch.

        The projectile keeps unit mass: M enters only through the drag rate Fr / M (gravity's
        acceleration does not depend on it), as in the batched flights. ``launch`` turns that
        rate, times its step, into the joint damping and the wind motor's gear.
        """
        self._rate = Fr / M
        self.named.data.ctrl["wind"] = W

    def set_target(self, X: float) -> None:
        self.named.data.mocap_pos["target", 0] = X

    def launch(self, ux: float, uy: float, *, step: float) -> tuple[np.ndarray, np.ndarray]:
        """Put the projectile at the origin with velocity (ux, uy), to fly with RK4 step ``step``.

        The flight runs in the model's scaled time (``flight`` module docstring): model step
        ``flight.SCALED_STEP``, drag rate ``step Fr / M``, launch velocity ``(ux, uy / step)``.

        Returns:
          The launch ``(qpos, qvel)`` (scaled).
        """
        rate = step * self._rate
        self._scale = step
        (x,), (z,) = self._dofs()
        model, data = self.model.ptr, self.data.ptr  # raw arrays: this runs once per dm_env episode
        model.dof_damping[x] = rate
        model.actuator_gear[self._wind_actuator(), 0] = -rate
        model.opt.timestep = flight.SCALED_STEP
        data.time = 0.0
        data.qpos[:] = 0.0
        data.qvel[:] = 0.0
        data.qvel[x] = ux
        data.qvel[z] = uy / step
        return data.qpos.copy(), data.qvel.copy()

    def _wind_actuator(self) -> int:
        return self.model.name2id("wind", "actuator")

    def fly(self, *, previous=None, history: bool = False):
        """Step until the projectile is back at height 0; see ``flight.fly`` (real x, height, time)."""
        x, z = self._dofs()
        model, data = self.model.ptr, self.data.ptr
        steps = flight.max_steps_for(float(data.qvel[z[0]]) if previous is None else float(previous[1][z[0]]),
                                     G=-float(model.opt.gravity[2]), dt=float(model.opt.timestep))
        return flight.fly(model, data, x=x, z=z, max_steps=steps, previous=previous,
                          history=history, scale=getattr(self, "_scale", 1.0))


def load_physics(G: float = 0.05) -> LauncherPhysics:
    """The launcher physics with gravity ``G`` (Table 3's by default) and the model's drag and mass."""
    physics = LauncherPhysics.from_xml_path(str(model_path("launcher")))
    physics.model.opt.gravity[:] = (0.0, 0.0, -G)
    (x,), _ = physics._dofs()
    model = physics.model
    physics.set_conditions(Fr=float(model.dof_damping[x]), W=0.0,
                           M=float(model.body_mass[model.name2id("projectile", "body")]))
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
