"""Reach around a wall with the actuated 2-link arm: a multi-step task where only the future pays.

The arm (``models/arm2_obstacle.xml``) starts near a rest pose right of a wall; the goal lies just
left of it. Each step the learner outputs a change of the joint targets (each joint at most
``max_step`` rad), the position servos track the new targets for ``control_interval`` seconds with
real MuJoCo contacts against the wall, and the observation is the joint angles. The reward of a
step is ``-(1 + d)``, d the fingertip-to-goal distance after it: every step costs, more when far.
Moving the tip straight at the goal drives it into the wall, so a learner that maximises the next
reward alone (gamma = 0) gets stuck there (d = 0.21); going around under the wall first increases
d, and pays only through the steps it saves later. The episode ends at the goal (d < ``tolerance``,
terminal) or after ``step_limit`` steps (truncated: not terminal, the learner still bootstraps).

Batched episodes end at different steps in different trials. The batch never waits: after
``step``, ``next_observations``, ``terminal`` and ``truncated`` say what happened in each trial,
and the next ``reset()`` starts a new episode only in the trials whose episode is over (drawn
from that trial's own stream), returning every trial's current observation. So a training step
is one control interval in every trial, and trial i's episodes are the same alone or batched.
"""

from __future__ import annotations

import dataclasses
import math
from collections import OrderedDict

import numpy as np
from dm_control.rl import control
from dm_env import specs

from somarm.streams import trial_generators, trial_ids_for
from somarm.tasks import actuation, arms
from somarm.tasks.base import TaskBase, check_actions
from somarm.tasks.pool import threads_here
from somarm.tasks.record import TaskRecord

__all__ = ["ObstacleParams", "Obstacle", "ObstaclePhysics", "ObstacleEnvTask", "RECORDS", "REST_POSE", "GOAL",
           "fingertips", "moves", "load_physics"]

#: The rest pose the episodes start near: elbow out to the right, fingertip at (0.68, 0.62).
REST_POSE = np.array([0.6565, 1.2635])
#: The goal, mirror image of the start's fingertip behind the wall (the model's ``goal`` geom).
GOAL = np.array([0.32, 0.62])
_LINKS = arms.LINK_LENGTHS[2]


@dataclasses.dataclass(frozen=True)
class ObstacleParams:
    """The task's knobs (this project's choices; with them the shortest path is 4 steps)."""

    max_step: float = 0.4  #: largest change of each joint target per step (rad)
    control_interval: float = 0.3  #: seconds the servos track the targets per step (whole 0.01 s)
    tolerance: float = 0.06  #: the goal is reached when the fingertip is closer than this
    step_limit: int = 20  #: steps after which an episode is cut off (truncated, not terminal)
    start_spread: float = 0.05  #: start angles are uniform within +- this of ``REST_POSE`` (rad)

    def __post_init__(self):
        bounds = {"max_step": (0.01, 1.0), "control_interval": (0.01, 10.0), "tolerance": (0.001, 0.5),
                  "start_spread": (0.0, 0.2)}
        for field, (low, high) in bounds.items():
            value = getattr(self, field)
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
                raise ValueError(f"{field} must be a finite number, got {value!r}")
            if not low <= value <= high:
                raise ValueError(f"{field} must be in [{low:g}, {high:g}], got {value!r}")
        if isinstance(self.step_limit, bool) or not isinstance(self.step_limit, int) or not 1 <= self.step_limit <= 1000:
            raise ValueError(f"step_limit must be a whole number in [1, 1000], got {self.step_limit!r}")


def fingertips(angles: np.ndarray) -> np.ndarray:
    """Fingertip (x, y) ``(..., 2)`` of joint angles ``(..., 2)``, by MuJoCo (as ``arms.fingertips``)."""
    return arms.fingertips(angles, 2)


def moves(max_step: float) -> np.ndarray:
    """The nine corner, edge and null moves of the action box, ``(9, 2)``: the searches' action set."""
    grid = np.array([-max_step, 0.0, max_step])
    return np.stack(np.meshgrid(grid, grid, indexing="ij"), axis=-1).reshape(-1, 2)


class Obstacle(TaskBase):
    """Batched multi-step episodes of ``reach2_obstacle`` (``somarm.protocols.EpisodicTask``).

    Args:
      params: an ``ObstacleParams``.
      n_trials, seed, trial_ids: as every batched task (trial i is the same alone or batched).
      backend: only "mujoco" (the contacts have no closed form).

    Raises:
      ValueError: another backend, or bad ``n_trials``/``trial_ids``.
    """

    name = "reach2_obstacle"
    episodic = True  #: episodes last several steps: ``step`` sets ``next_observations``/``terminal``
    actuated = True  #: the servos track each step's targets for ``control_interval``
    goal = GOAL  #: where the fingertip must go, (x, y)

    def __init__(self, params: ObstacleParams, *, n_trials: int = 1, seed: int = 0,
                 trial_ids: np.ndarray | None = None, backend: str = "mujoco"):
        if backend != "mujoco":
            raise ValueError(f"reach2_obstacle needs the mujoco backend (contacts), got backend {backend!r}")
        self.params, self.backend, self.seed = params, backend, seed
        self.trial_ids = trial_ids_for(n_trials, trial_ids)
        self.n_trials = int(self.trial_ids.size)
        self._generators = trial_generators(seed, self.trial_ids, "task")
        self.observation_low, self.observation_high = np.full(2, -np.pi), np.full(2, np.pi)
        self.action_low, self.action_high = np.full(2, -params.max_step), np.full(2, params.max_step)
        # action_periodic stays TaskBase's none: the actions are angle steps, not angles.
        self.control_steps = actuation.steps_of(params.control_interval, arms.TIMESTEP)
        self._qpos = np.zeros((self.n_trials, 2))
        self._qvel = np.zeros((self.n_trials, 2))
        self._steps = np.zeros(self.n_trials, dtype=np.int64)
        self._over = np.ones(self.n_trials, dtype=bool)  # every trial starts a new episode at reset()
        self._started = False
        self.next_observations = np.zeros((self.n_trials, 2))  #: angles after the last step
        self.terminal = np.zeros(self.n_trials, dtype=bool)  #: the last step reached the goal
        self.truncated = np.zeros(self.n_trials, dtype=bool)  #: the last step hit the step limit
        self.t = 0  #: steps taken (the learner's t)

    def __repr__(self) -> str:
        return f"Obstacle({self.params!r}, n_trials={self.n_trials})"

    # -- physics -------------------------------------------------------------------------
    def _servos(self, n: int) -> actuation.Servos:
        return actuation.servos("arm2_obstacle", threads_here(arms.THREADS) if n > 512 else 1)

    def advance(self, qpos: np.ndarray, qvel: np.ndarray, actions: np.ndarray, *, path: bool = False):
        """One control interval from ``(qpos, qvel)`` ``(n, 2)`` with target changes ``actions`` ``(n, 2)``.

        Returns:
          ``(qpos, qvel)`` after it, or with ``path`` the angles after every timestep ``(n, control_steps, 2)``.
        """
        targets = np.clip(qpos + actions, -np.pi, np.pi)
        return self._servos(len(qpos)).run(qpos, qvel, targets, self.control_steps, path=path)

    def distances(self, angles: np.ndarray) -> np.ndarray:
        """Fingertip-to-goal distances ``(...)`` of joint angles ``(..., 2)``."""
        return np.linalg.norm(fingertips(angles) - GOAL, axis=-1)

    def reward_of(self, distances: np.ndarray) -> np.ndarray:
        """The step reward ``-(1 + d)`` for distances ``d`` after the step."""
        return -(1.0 + distances)

    def start_poses(self, rng: np.random.Generator, n: int) -> np.ndarray:
        """``n`` start poses ``(n, 2)``: ``REST_POSE`` plus uniform noise of +- ``start_spread``."""
        spread = self.params.start_spread
        return REST_POSE + spread * (2.0 * rng.random((int(n), 2)) - 1.0)

    # -- the BatchedTask protocol --------------------------------------------------------
    def reset(self) -> np.ndarray:
        """Start new episodes in the trials whose episode is over; every trial's angles ``(n_trials, 2)``."""
        for i in np.flatnonzero(self._over):
            self._qpos[i] = self.start_poses(self._generators[i], 1)[0]
            self._qvel[i] = 0.0
            self._steps[i] = 0
        self._over[:] = False
        self._started = True
        return self._qpos.copy()

    def step(self, actions: np.ndarray) -> np.ndarray:
        """Rewards ``(n_trials,)`` for target changes ``(n_trials, 2)``; sets the episode flags.

        Raises:
          ValueError: no ``reset`` before, or actions of the wrong shape, non-finite or out of bounds.
        """
        if not self._started:
            raise ValueError(f"{self.name}: call reset() before step()")
        actions = check_actions("actions", actions, self.action_low, self.action_high)
        if actions.shape != (self.n_trials, 2):
            raise ValueError(f"actions must have shape ({self.n_trials}, 2), got {actions.shape}")
        self._qpos, self._qvel = self.advance(self._qpos, self._qvel, actions)
        self._steps += 1
        distances = self.distances(self._qpos)
        self.terminal = distances < self.params.tolerance
        self.truncated = ~self.terminal & (self._steps >= self.params.step_limit)
        self._over = self.terminal | self.truncated
        self.next_observations = self._qpos.copy()
        self._started = False
        self.t += 1
        return self.reward_of(distances)

    def evaluate(self, observations: np.ndarray, actions: np.ndarray) -> np.ndarray:
        """Rewards ``(...)`` of one step from rest at angles ``(..., 2)`` with changes ``(..., 2)``. Pure."""
        observations = np.asarray(observations, dtype=np.float64)
        if observations.ndim == 0 or observations.shape[-1] != 2 or not np.isfinite(observations).all():
            raise ValueError(f"observations must be finite with shape (..., 2), got {observations.shape}")
        actions = check_actions("actions", actions, self.action_low, self.action_high)
        shape = np.broadcast_shapes(observations.shape[:-1], actions.shape[:-1])
        qpos = np.broadcast_to(observations, (*shape, 2)).reshape(-1, 2)
        qpos_next, _ = self.advance(qpos, np.zeros_like(qpos), np.broadcast_to(actions, (*shape, 2)).reshape(-1, 2))
        return self.reward_of(self.distances(qpos_next)).reshape(shape)

    def sample_observations(self, rng: np.random.Generator, n: int) -> np.ndarray:
        """``n`` start observations ``(n, 2)`` drawn with ``rng``."""
        return self.start_poses(rng, n)

    def sample_starts(self, rng: np.random.Generator, n: int) -> np.ndarray:
        """``n`` episode starts for ``run_episodes``: start poses ``(n, 2)``."""
        return self.start_poses(rng, n)

    # -- whole episodes --------------------------------------------------------------------
    def run_episodes(self, policy, starts: np.ndarray, *, paths: bool = False) -> dict[str, np.ndarray]:
        """Run episodes from ``starts`` ``(m, 2)`` to the goal or the step limit, all in one batch.

        Args:
          policy: maps angles ``(m, 2)`` to target changes ``(m, 2)`` (called once per step).
          starts: start angles, one episode each.
          paths: also return every timestep's angles.

        Returns:
          ``{"success": (m,) bool, "length": (m,) steps taken, "returns": (m,) undiscounted}`` and with
          ``paths`` ``"path": (m, 1 + step_limit * control_steps, 2)`` (held at the last pose once done).
        """
        qpos = np.array(starts, dtype=np.float64).reshape(-1, 2)
        m = len(qpos)
        qvel = np.zeros_like(qpos)
        running = np.ones(m, dtype=bool)
        length = np.zeros(m, dtype=np.int64)
        success = np.zeros(m, dtype=bool)
        returns = np.zeros(m)
        trace = [qpos[:, None, :].copy()] if paths else None
        for _ in range(self.params.step_limit):
            actions = np.clip(np.asarray(policy(qpos), dtype=np.float64), self.action_low, self.action_high)
            steps, new_v = self.advance(qpos, qvel, actions, path=paths)
            new_q = steps[:, -1] if paths else steps
            if paths:
                trace.append(np.where(running[:, None, None], steps, qpos[:, None, :]))
            distances = self.distances(new_q)
            returns += np.where(running, self.reward_of(distances), 0.0)
            length += running
            qpos = np.where(running[:, None], new_q, qpos)
            qvel = np.where(running[:, None], new_v, qvel)
            reached = running & (distances < self.params.tolerance)
            success |= reached
            running &= ~reached
            if not running.any():
                break
        out = {"success": success, "length": length, "returns": returns}
        if paths:
            path = np.concatenate(trace, axis=1)
            full = 1 + self.params.step_limit * self.control_steps
            out["path"] = np.concatenate([path, np.repeat(path[:, -1:], full - path.shape[1], axis=1)], axis=1)
        return out


class ObstaclePhysics(arms.ArmPhysics):
    """dm_control physics of ``models/arm2_obstacle.xml``: the arm, the wall and the fixed goal."""

    def goal(self) -> np.ndarray:
        """(x, y) of the goal marker (a fixed geom)."""
        return self.named.data.geom_xpos["goal", :2].copy()

    def wall_penetration(self) -> float:
        """The deepest overlap of a link with the wall now (0 if they do not touch)."""
        depths = [-self.data.contact[k].dist for k in range(self.data.ncon)]
        return max([0.0, *depths])


def load_physics() -> ObstaclePhysics:
    """The dm_control physics of ``models/arm2_obstacle.xml``."""
    from somarm.tasks.assets import model_path

    return ObstaclePhysics.from_xml_path(str(model_path("arm2_obstacle")))


class ObstacleEnvTask(control.Task):
    """dm_env side of ``reach2_obstacle``: one dm_env episode is one episode of trial 0 of a batch.

    The start pose of episode k is the one trial 0 of a batch with the same seed starts its k-th
    episode from; the environment steps ``control_steps`` timesteps per action (``n_sub_steps``), ends
    the episode at the goal with discount 0, and cuts it at the step limit with discount 1.
    """

    def __init__(self, batched: Obstacle):
        self.batched = batched
        self._steps = 0
        self.sub_steps = batched.control_steps  #: timesteps per dm_env step (``tasks.load`` reads it)

    def initialize_episode(self, physics: ObstaclePhysics) -> None:
        self.batched._over[:] = True  # a new episode whatever state the batch was left in
        physics.set_angles(self.batched.reset()[0])
        physics.set_targets(physics.angles())
        self._steps = 0

    def before_step(self, action, physics: ObstaclePhysics) -> None:
        action = check_actions("action", action, self.batched.action_low, self.batched.action_high)
        if action.shape != (2,):
            raise ValueError(f"action must have shape (2,), got {action.shape}")
        physics.set_targets(np.clip(physics.angles() + action, -np.pi, np.pi))

    def after_step(self, physics: ObstaclePhysics) -> None:
        self._steps += 1
        self.batched.t += 1

    def action_spec(self, physics):
        return specs.BoundedArray((2,), np.float64, self.batched.action_low, self.batched.action_high,
                                  name="action")

    def observation_spec(self, physics):
        return OrderedDict({"angles": specs.BoundedArray((2,), np.float64, self.batched.observation_low,
                                                         self.batched.observation_high, name="angles")})

    def get_observation(self, physics: ObstaclePhysics):
        return OrderedDict({"angles": physics.angles()})

    def _distance(self, physics: ObstaclePhysics) -> float:
        return float(np.linalg.norm(physics.fingertip() - GOAL))

    def get_reward(self, physics: ObstaclePhysics) -> float:
        return float(self.batched.reward_of(np.array(self._distance(physics))))

    def get_termination(self, physics: ObstaclePhysics):
        if self._steps and self._distance(physics) < self.batched.params.tolerance:
            return 0.0  # the goal: terminal
        if self._steps >= self.batched.params.step_limit:
            return 1.0  # the step limit: truncated, the future still counts
        return None


RECORDS = (
    TaskRecord(
        name="reach2_obstacle",
        summary="actuated 2-link arm steps around a wall to a goal (multi-step, delayed reward); "
                "obs 2 angles, action 2 target changes",
        params=ObstacleParams,
        settable=("max_step", "control_interval", "tolerance", "step_limit", "start_spread"),
        make=lambda params, **kwargs: Obstacle(params, **kwargs),
        environment=lambda batched: (load_physics(), ObstacleEnvTask(batched)),
        preset="obstacle",
        n_steps=20_000,
        model="arm2_obstacle",
        observation_labels=("theta1 (rad)", "theta2 (rad)"),
        action_labels=("change of theta1's target (normalised)", "change of theta2's target (normalised)"),
        backends=("mujoco",),
        episodic=Obstacle.episodic,  # the class owns the fact; the record lists it without building a task
    ),
)
