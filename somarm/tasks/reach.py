"""Reach a goal on a circle with the 2-link or the 20-link arm (Smith 2002, section 5.1).

The observation is the goal (x, y), drawn uniformly on the goal circle; the action is the
joint angles to move to; the reward is minus the fingertip-to-goal distance. The circle is
this project's choice (the paper gives none): centre (0.5, 0.5), radius 0.25, inside the unit
square and wholly reachable by both arms (arm2 reaches 0.8 and arm20 1.0 from the base at (0.5, 0)).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from somarm import kinematics
from somarm.tasks import arms
from somarm.tasks.base import OneStepEnvTask, OneStepTask
from somarm.tasks.record import TaskRecord

__all__ = ["ReachParams", "Reach", "ReachEnvTask", "ArmEnvTask", "RECORDS", "ARM_ACTION_LABELS", "fingertips",
           "goal_circle_points"]

fingertips = arms.fingertips


@dataclasses.dataclass(frozen=True)
class ReachParams:
    """The goal circle (this project's choice; the paper does not give it)."""

    centre_x: float = 0.5  #: x of the circle's centre
    centre_y: float = 0.5  #: y of the circle's centre
    radius: float = 0.25  #: radius; the circle must stay in the unit square and within reach

    def __post_init__(self):
        for field in ("centre_x", "centre_y", "radius"):
            value = getattr(self, field)
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
                raise ValueError(f"{field} must be a finite number, got {value!r}")
        if self.radius <= 0:
            raise ValueError(f"radius must be > 0, got {self.radius!r}")
        if not (self.radius <= self.centre_x <= 1 - self.radius and self.radius <= self.centre_y <= 1 - self.radius):
            raise ValueError(f"the goal circle (centre ({self.centre_x}, {self.centre_y}), radius "
                             f"{self.radius}) must lie inside the unit square")

    def check_reachable(self, lengths: np.ndarray) -> None:
        """Raise ValueError unless every point of the circle is within the arm's reach."""
        far = math.hypot(self.centre_x - kinematics.BASE[0], self.centre_y - kinematics.BASE[1])
        outer = float(np.sum(lengths))
        inner = max(0.0, 2 * float(np.max(lengths)) - outer)
        if far + self.radius > outer or far - self.radius < inner:
            raise ValueError(f"the goal circle must lie within the arm's reach ({inner:g} to {outer:g} "
                             f"from the base), but spans {far - self.radius:g} to {far + self.radius:g}")


def goal_circle_points(params: ReachParams, angles: np.ndarray) -> np.ndarray:
    """Points of the goal circle at polar angles ``(...)`` (radians), shape ``(..., 2)``."""
    angles = np.asarray(angles, dtype=np.float64)
    return np.stack([params.centre_x + params.radius * np.cos(angles),
                     params.centre_y + params.radius * np.sin(angles)], axis=-1)


def _tip(actions: np.ndarray, n_links: int, backend: str) -> np.ndarray:
    if backend == "analytic":
        return kinematics.forward(actions, arms.LINK_LENGTHS[n_links])
    return arms.fingertips(actions, n_links)


class Reach(OneStepTask):
    """Batched reach task for an arm of ``n_links`` links (``reach2``, ``reach20``)."""

    uniform_width = 1

    def __init__(self, params: ReachParams, *, n_links: int, **kwargs):
        self.name = f"reach{n_links}"
        self.n_links = n_links
        params.check_reachable(arms.LINK_LENGTHS[n_links])
        self.observation_low, self.observation_high = np.zeros(2), np.ones(2)
        self.action_low, self.action_high = np.full(n_links, -np.pi), np.full(n_links, np.pi)
        super().__init__(params, **kwargs)

    def observations_from(self, uniforms: np.ndarray) -> np.ndarray:
        return goal_circle_points(self.params, 2.0 * np.pi * uniforms[:, 0])

    def rewards(self, observations: np.ndarray, actions: np.ndarray) -> np.ndarray:
        tips = _tip(actions, self.n_links, self.backend)
        return -np.linalg.norm(tips - observations, axis=-1)


class ArmEnvTask(OneStepEnvTask):
    """dm_env side of the arm tasks: the arm moves to the action's angles, the reward is read back."""

    def apply_action(self, physics: arms.ArmPhysics, action: np.ndarray) -> None:
        self._angles = action.copy()
        physics.set_angles(action)

    def after_step(self, physics: arms.ArmPhysics) -> None:
        # physics.step ran mj_step from rest with no force; set the pose again so that the
        # fingertip read next is exactly the setpoint's, whatever the integrator did.
        physics.set_angles(self._angles)
        super().after_step(physics)

    def reward_from_physics(self, physics: arms.ArmPhysics, observation: np.ndarray) -> float:
        return -physics.fingertip_to_goal()


class ReachEnvTask(ArmEnvTask):
    """dm_env side of the reach tasks: the goal marker moves to the observed goal."""

    def __init__(self, batched: Reach):
        super().__init__(batched, observation_key="goal")

    def apply_observation(self, physics: arms.ArmPhysics, observation: np.ndarray) -> None:
        physics.set_goal(observation)


#: Axis labels of an arm's first two (normalised) joint angles in the run figures.
ARM_ACTION_LABELS = ("theta1 (normalised from [-pi, pi])", "theta2 (normalised)")


def _reach_environment(batched: Reach) -> tuple[arms.ArmPhysics, ReachEnvTask]:
    return arms.load_physics(batched.n_links), ReachEnvTask(batched)


def _record(n_links: int, figure: str) -> TaskRecord:
    return TaskRecord(
        name=f"reach{n_links}",
        summary=f"{n_links}-link arm reaches a goal on a circle ({figure}); obs goal (x, y), "
                f"action {n_links} angles",
        params=ReachParams,
        settable=("centre_x", "centre_y", "radius"),
        make=lambda params, **kwargs: Reach(params, n_links=n_links, **kwargs),
        environment=_reach_environment,
        preset="table1",
        n_steps=50_000,
        model=f"arm{n_links}",
        observation_labels=("goal x", "goal y"),
        action_labels=ARM_ACTION_LABELS,
        view="sweep" if n_links == 20 else "goals",
    )


RECORDS = (_record(2, "Fig. 5"), _record(20, "Fig. 11"))
