"""Reach a goal on a circle with the 2-link or the 20-link arm (Smith 2002, section 5.1).

The observation is the goal (x, y), drawn uniformly on the goal circle; the action is the
joint angles to move to; the reward is minus the fingertip-to-goal distance. The circle is
this project's choice (the paper gives none): centre (0.5, 0.5), radius 0.25, inside the unit
square and wholly reachable by both arms (arm2 reaches 0.8 and arm20 1.0 from the base at (0.5, 0)).

``dynamics`` says how the arm gets there: ``kinematic`` (the paper's, the default) sets the
angles as a setpoint; ``actuated`` hands them to the joints' position servos as targets and
integrates ``settle_time`` seconds (0.2 by default, before the servos arrive) from the start pose
(every angle 0: the arm straight along x), and the reward is read where the fingertip then is.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from somarm.tasks import actuation, arms, kinematics
from somarm.tasks.base import OneStepEnvTask, OneStepTask
from somarm.tasks.pool import threads_here
from somarm.tasks.record import TaskRecord

__all__ = ["DYNAMICS", "ReachParams", "Reach", "ReachEnvTask", "ArmEnvTask", "RECORDS", "ARM_ACTION_LABELS",
           "fingertips", "goal_circle_points"]

fingertips = arms.fingertips

#: How an action moves the arm: a kinematic setpoint, or joint targets for the position servos.
DYNAMICS: tuple[str, ...] = ("kinematic", "actuated")


@dataclasses.dataclass(frozen=True)
class ReachParams:
    """The goal circle (this project's choice; the paper does not give it)."""

    centre_x: float = 0.5  #: x of the circle's centre
    centre_y: float = 0.5  #: y of the circle's centre
    radius: float = 0.25  #: radius; the circle must stay in the unit square and within reach
    dynamics: str = "kinematic"  #: ``kinematic`` (setpoint, the paper's) or ``actuated`` (servo targets)
    #: Seconds the servos track the targets before the reward is read (``actuated`` only), rounded to
    #: whole timesteps of 0.01. At the default 0.2 s the servos have not arrived: from the start pose a
    #: joint has covered about 0.93 of its way, so the reached pose is the physics' answer, not the
    #: target's (the fingertip 0.085 from the target's on average, up to 0.17), and every goal of the
    #: circle is reached with the elbow up by targets 0.39 rad or more inside [-pi, pi]. At 1 s a step of
    #: any size settles within 1e-5.
    settle_time: float = 0.2
    #: ``actuated`` only: the servo targets range over +-target_scale x pi, while the joints stay limited to
    #: [-pi, pi]. A servo covers about 0.92 of its way in the default settle time, so a joint angle near a
    #: limit needs a target beyond it: with targets in [-pi, pi] an action map that forms with the elbow on
    #: that side piles against the bound. 1 (the default) is the box of the kinematic arm.
    target_scale: float = 1.0

    def __post_init__(self):
        if self.dynamics not in DYNAMICS:
            raise ValueError(f"dynamics must be one of {', '.join(DYNAMICS)}, got {self.dynamics!r}")
        for field in ("centre_x", "centre_y", "radius", "settle_time", "target_scale"):
            value = getattr(self, field)
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
                raise ValueError(f"{field} must be a finite number, got {value!r}")
        if self.radius <= 0:
            raise ValueError(f"radius must be > 0, got {self.radius!r}")
        if not 0.01 <= self.settle_time <= 100:
            raise ValueError(f"settle_time must be in [0.01, 100] seconds, got {self.settle_time!r}")
        if not 1 <= self.target_scale <= 2:
            raise ValueError(f"target_scale must be in [1, 2], got {self.target_scale!r}")
        if self.target_scale != 1 and self.dynamics != "actuated":
            raise ValueError("target_scale other than 1 needs dynamics=actuated (kinematic actions are the angles)")
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
    """Batched reach task for an arm of ``n_links`` links (``reach2``, ``reach20``).

    Raises:
      ValueError: a goal circle out of reach, or ``dynamics=actuated`` with the analytic backend.
    """

    uniform_width = 1

    def __init__(self, params: ReachParams, *, n_links: int, **kwargs):
        self.name = f"reach{n_links}"
        self.n_links = n_links
        params.check_reachable(arms.LINK_LENGTHS[n_links])
        if params.dynamics == "actuated" and kwargs.get("backend") == "analytic":
            raise ValueError("dynamics=actuated needs the mujoco backend (no closed form integrates the servos)")
        self.observation_low, self.observation_high = np.zeros(2), np.ones(2)
        limit = params.target_scale * np.pi
        self.action_low, self.action_high = np.full(n_links, -limit), np.full(n_links, limit)
        super().__init__(params, **kwargs)

    @property
    def action_periodic(self) -> np.ndarray:
        """Kinematic: every joint angle, since [-pi, pi] is one turn and -pi and pi are the same pose.
        Actuated: none, since a servo target of -pi turns the joint the other way round from one of pi."""
        return np.full(self.n_links, not self.actuated, dtype=np.bool_)

    @property
    def actuated(self) -> bool:
        """``dynamics=actuated``: the joints' servos track the actions as targets."""
        return self.params.dynamics == "actuated"

    @property
    def settle_steps(self) -> int:
        """Timesteps the servos integrate per action (``actuated`` only)."""
        return actuation.steps_of(self.params.settle_time, arms.TIMESTEP)

    def reached_angles(self, actions: np.ndarray, *, path: bool = False) -> np.ndarray:
        """Where the joints are when the reward is read, ``(..., n_links)`` for actions ``(..., n_links)``.

        Kinematic: the actions themselves. Actuated: the servos' angles after ``settle_time`` from the
        start pose; with ``path`` the angles after every timestep, ``(..., settle_steps, n_links)``.
        """
        actions = np.asarray(actions, dtype=np.float64)
        if not self.actuated:
            return actions[..., None, :] if path else actions
        flat = actions.reshape(-1, self.n_links)
        threads = threads_here(arms.THREADS) if len(flat) > 512 else 1
        start = np.zeros_like(flat)
        limit = None if self.params.target_scale == 1 else float(self.action_high[0])
        servos = actuation.servos(f"arm{self.n_links}", threads, ctrl_limit=limit)
        result = servos.run(start, start, flat, self.settle_steps, path=path)
        if path:
            return result[0].reshape(*actions.shape[:-1], self.settle_steps, self.n_links)
        return result[0].reshape(actions.shape)

    def observations_from(self, uniforms: np.ndarray) -> np.ndarray:
        return goal_circle_points(self.params, 2.0 * np.pi * uniforms[:, 0])

    def rewards(self, observations: np.ndarray, actions: np.ndarray) -> np.ndarray:
        tips = _tip(self.reached_angles(actions), self.n_links, self.backend)
        return -np.linalg.norm(tips - observations, axis=-1)


class ArmEnvTask(OneStepEnvTask):
    """dm_env side of the arm tasks: the arm moves to the action's angles, the reward is read back.

    Actuated (``dynamics=actuated``): each episode starts at rest in the start pose (the model's
    ``qpos0``, every angle 0, restored by the environment's reset), the action becomes the servos'
    targets and the environment steps ``settle_steps`` timesteps per action.
    """

    def apply_action(self, physics: arms.ArmPhysics, action: np.ndarray) -> None:
        self._angles = action.copy()
        if self.batched.actuated:
            physics.set_targets(action)
        else:
            physics.set_angles(action)

    def after_step(self, physics: arms.ArmPhysics) -> None:
        if not self.batched.actuated:
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
        #: Timesteps per dm_env step (``tasks.load`` reads it): the settle time when actuated.
        self.sub_steps = batched.settle_steps if batched.actuated else 1

    def apply_observation(self, physics: arms.ArmPhysics, observation: np.ndarray) -> None:
        physics.set_goal(observation)


#: Axis labels of an arm's first two (normalised) joint angles in the run figures.
ARM_ACTION_LABELS = ("theta1 (normalised from [-pi, pi])", "theta2 (normalised)")


def _reach_environment(batched: Reach) -> tuple[arms.ArmPhysics, ReachEnvTask]:
    physics = arms.load_physics(batched.n_links)
    if batched.params.target_scale != 1:  # the servos take the task's wider targets (ReachParams.target_scale)
        physics.model.actuator_ctrlrange[:] = (batched.action_low[0], batched.action_high[0])
    return physics, ReachEnvTask(batched)


def _record(n_links: int, figure: str) -> TaskRecord:
    return TaskRecord(
        name=f"reach{n_links}",
        summary=f"{n_links}-link arm reaches a goal on a circle ({figure}); obs goal (x, y), "
                f"action {n_links} angles",
        params=ReachParams,
        settable=("centre_x", "centre_y", "radius", "dynamics", "settle_time", "target_scale"),
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
