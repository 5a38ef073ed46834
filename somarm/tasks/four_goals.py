"""Four goals chosen by quadrant, moved part-way through training (Smith 2002, Fig. 12).

The observation is uniform in the unit square; the goal is one of four positions chosen by
the observation's quadrant; the reward is minus the fingertip-to-goal distance (2-link arm).
When the task's step counter reaches ``switch_step`` the four goals move; the mapping from
quadrant to goal stays. Fig. 12 shows crosses roughly in the quadrants but gives no numbers:
the positions below are this project's choice, all inside the unit square and within reach.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from somarm.tasks import arms
from somarm.tasks.base import OneStepTask
from somarm.tasks.reach import ARM_ACTION_LABELS, ArmEnvTask, _tip
from somarm.tasks.record import TaskRecord

__all__ = ["GOALS_BEFORE", "GOALS_AFTER", "FourGoalsParams", "FourGoals", "FourGoalsEnvTask", "quadrants",
           "RECORDS"]

#: Goals before the move, ordered top-left, top-right, bottom-left, bottom-right quadrant.
GOALS_BEFORE: tuple[tuple[float, float], ...] = ((0.3, 0.7), (0.7, 0.7), (0.3, 0.3), (0.7, 0.3))
#: Goals after the move: each turned 45 degrees clockwise about (0.5, 0.5), at radius 0.25.
GOALS_AFTER: tuple[tuple[float, float], ...] = ((0.5, 0.75), (0.75, 0.5), (0.25, 0.5), (0.5, 0.25))


def _goal_array(name: str, goals) -> np.ndarray:
    try:
        array = np.asarray(goals, dtype=np.float64)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be four (x, y) pairs, got {goals!r}") from None
    if array.shape != (4, 2) or not np.isfinite(array).all():
        raise ValueError(f"{name} must be four finite (x, y) pairs, got {goals!r}")
    if (array < 0).any() or (array > 1).any():
        raise ValueError(f"{name} must lie inside the unit square, got {goals!r}")
    reach = float(arms.LINK_LENGTHS[2].sum())
    if (np.hypot(array[:, 0] - 0.5, array[:, 1]) > reach).any():
        raise ValueError(f"{name} must lie within the arm's reach ({reach:g} from (0.5, 0)), got {goals!r}")
    return array


@dataclasses.dataclass(frozen=True)
class FourGoalsParams:
    """When the goals move, and where they are before and after (this project's positions)."""

    switch_step: int = 20_000  #: the step at which the goals move (Fig. 13: t = 20,000)
    goals_before: tuple[tuple[float, float], ...] = GOALS_BEFORE  #: TL, TR, BL, BR goals first
    goals_after: tuple[tuple[float, float], ...] = GOALS_AFTER  #: TL, TR, BL, BR goals after the move

    def __post_init__(self):
        step = self.switch_step
        if isinstance(step, bool) or not isinstance(step, (int, np.integer)) or step < 0:
            raise ValueError(f"switch_step must be a whole number >= 0, got {step!r}")
        for name in ("goals_before", "goals_after"):
            # Lists from JSON or the CLI become tuples, so the params stay hashable and frozen.
            array = _goal_array(name, getattr(self, name))
            object.__setattr__(self, name, tuple(map(tuple, array.tolist())))

    def goals(self, t: int) -> np.ndarray:
        """The four goals ``(4, 2)`` in force at step ``t``."""
        return np.asarray(self.goals_after if t >= self.switch_step else self.goals_before)


def quadrants(observations: np.ndarray) -> np.ndarray:
    """Quadrant index of each observation ``(..., 2)``: 0 TL, 1 TR, 2 BL, 3 BR."""
    return (observations[..., 0] >= 0.5).astype(np.intp) + 2 * (observations[..., 1] < 0.5)


class FourGoals(OneStepTask):
    """Batched four-goals task on the 2-link arm."""

    name = "four_goals"
    uniform_width = 2
    n_links = 2

    def __init__(self, params: FourGoalsParams, **kwargs):
        self.observation_low, self.observation_high = np.zeros(2), np.ones(2)
        self.action_low, self.action_high = np.full(2, -np.pi), np.full(2, np.pi)
        super().__init__(params, **kwargs)

    @property
    def action_periodic(self) -> np.ndarray:
        """Both joint angles: [-pi, pi] is one turn, so -pi and pi are the same pose."""
        return np.ones(self.n_links, dtype=np.bool_)

    def goals_for(self, observations: np.ndarray) -> np.ndarray:
        """The goal ``(..., 2)`` of each observation in the current phase."""
        return self.params.goals(self.t)[quadrants(observations)]

    def observations_from(self, uniforms: np.ndarray) -> np.ndarray:
        return uniforms.copy()

    def rewards(self, observations: np.ndarray, actions: np.ndarray) -> np.ndarray:
        tips = _tip(actions, self.n_links, self.backend)
        return -np.linalg.norm(tips - self.goals_for(observations), axis=-1)


class FourGoalsEnvTask(ArmEnvTask):
    """dm_env side: the goal marker moves to the quadrant's goal of the current phase."""

    def __init__(self, batched: FourGoals):
        super().__init__(batched, observation_key="position")

    def apply_observation(self, physics: arms.ArmPhysics, observation: np.ndarray) -> None:
        physics.set_goal(self.batched.goals_for(observation))


RECORDS = (
    TaskRecord(
        name="four_goals",
        summary="2-link arm, obs in the unit square, one goal per quadrant, goals move (Fig. 12)",
        params=FourGoalsParams,
        settable=("switch_step", "goals_before", "goals_after"),
        make=FourGoals,
        environment=lambda batched: (arms.load_physics(2), FourGoalsEnvTask(batched)),
        preset="table2",
        n_steps=40_000,
        model="arm2",
        observation_labels=("input x", "input y"),
        action_labels=ARM_ACTION_LABELS,
    ),
)
