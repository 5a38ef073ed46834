"""The launcher model in dm_control: one projectile, its target, and the throw tasks' dm_env side."""

from __future__ import annotations

import numpy as np
from dm_control import mujoco as dm_mujoco

from somarm.tasks import flight
from somarm.tasks.assets import model_path
from somarm.tasks.base import OneStepEnvTask
from somarm.tasks.throw import TABLE3, Throw, ThrowParams, _check_velocities, throw_rewards

__all__ = ["LauncherPhysics", "ThrowEnvTask", "load_physics", "simulate_trajectory"]


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

    def target(self) -> float:
        return float(self.named.data.mocap_pos["target", 0])

    def projectile_position(self) -> np.ndarray:
        """(x, height) of the projectile."""
        return np.array([self.named.data.qpos["x"], self.named.data.qpos["height"]]).ravel()

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


def load_physics(params: ThrowParams = TABLE3) -> LauncherPhysics:
    """The launcher physics with the gravity, drag, wind and mass of ``params``."""
    physics = LauncherPhysics.from_xml_path(str(model_path("launcher")))
    physics.model.opt.gravity[:] = (0.0, 0.0, -params.G)
    physics.set_conditions(Fr=params.Fr, W=params.W, M=params.M)
    return physics


def simulate_trajectory(ux: float, uy: float, params: ThrowParams = TABLE3, *,
                        dt: float | None = None) -> tuple[np.ndarray, np.ndarray]:
    """One throw simulated in MuJoCo, for animation: every step, ending at the landing point.

    Args:
      ux, uy: launch velocity in [0, 1].
      params: the environment (G, Fr, W, M, X; the tolerance picks the step when ``dt`` is None).
      dt: RK4 step; default: the step the tasks use for this throw (``flight.step_for``).

    Returns:
      ``(times (T,), xy (T, 2))``: time and (x, height) at launch, after every step, and at the
      located landing point (the last row, height 0).

    Raises:
      ValueError: velocities outside [0, 1] or a step that is not > 0.
    """
    ux_a, uy_a = _check_velocities(ux, uy)
    if ux_a.shape != ():
        raise ValueError(f"ux and uy must be single numbers, got shape {ux_a.shape}")
    step = float(flight.step_for(ux_a, params.W, params.Fr / params.M, tolerance=params.tolerance))
    if dt is not None:
        if not (isinstance(dt, (int, float)) and np.isfinite(dt) and dt > 0):
            raise ValueError(f"dt must be a number > 0, got {dt!r}")
        step = float(dt)
    physics = load_physics(params)
    physics.set_conditions(Fr=params.Fr, W=params.W, M=params.M)
    physics.set_target(params.X)
    physics.launch(float(ux_a), float(uy_a), step=step)
    _, times, qpos = physics.fly(history=True)
    x, z = physics._dofs()
    return times, np.stack([qpos[:, x[0]], qpos[:, z[0]]], axis=-1)


class ThrowEnvTask(OneStepEnvTask):
    """dm_env side of the throw tasks: launch, fly in MuJoCo until the landing, reward."""

    def __init__(self, batched: Throw):
        super().__init__(batched, observation_key="conditions")
        self._conditions: dict = {}

    def apply_observation(self, physics: LauncherPhysics, observation: np.ndarray) -> None:
        c = self.batched.conditions(observation)
        self._conditions = {k: float(v) for k, v in c.items()}
        physics.set_conditions(Fr=self._conditions["Fr"], W=self._conditions["W"], M=self._conditions["M"])
        physics.set_target(self._conditions["X"])

    def apply_action(self, physics: LauncherPhysics, action: np.ndarray) -> None:
        c = self._conditions
        self._velocity = (float(action[0]), float(action[1]))
        step = float(flight.step_for(self._velocity[0], c["W"], c["Fr"] / c["M"],
                                     tolerance=self.batched.params.tolerance))
        self._launch = physics.launch(*self._velocity, step=step)

    def reward_from_physics(self, physics: LauncherPhysics, observation: np.ndarray) -> float:
        # physics.step took the first step of the flight; fly on from there until the landing.
        landing = float(physics.fly(previous=self._launch)[0])
        ux, uy = self._velocity
        return float(throw_rewards(landing, self._conditions["X"], ux, uy,
                                   punish_low=self.batched.params.punish_low))
