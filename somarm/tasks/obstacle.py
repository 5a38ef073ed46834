"""Reach around a wall with the actuated 2-link arm: a multi-step task where only the future pays.

A wall stands over the base (``models/arm2_obstacle.xml``). Each episode starts at rest in a pose
drawn on one side of the wall, and its goal is drawn over a region behind the wall, on the other
side; the observation is the joint angles and the goal's (x, y), so the learner knows where to go.
Each step the learner outputs a change of the joint targets (each joint at most ``max_step`` rad),
the position servos track the new targets for ``control_interval`` seconds with real MuJoCo
contacts against the wall. The reward of a step is ``-(1 + d)``, d the fingertip-to-goal distance
after it: every step costs, more when far. Moving the tip straight at the goal drives it into the
wall, so a learner that maximises the next reward alone (gamma = 0) gets stuck there; going around
folds the elbow to pass under the wall, first moving away, and pays only through the steps it
saves later. The episode ends at the goal (d < ``tolerance``, terminal) or after ``step_limit``
steps (truncated: not terminal, the learner still bootstraps).

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
from somarm.tasks.assets import model_path
from somarm.tasks.base import TaskBase, check_actions
from somarm.tasks.obstacle_geometry import fingertips, touches_wall
from somarm.tasks.pool import threads_here
from somarm.tasks.record import TaskRecord

__all__ = ["ObstacleParams", "Obstacle", "ObstaclePhysics", "ObstacleEnvTask", "RECORDS", "REST_POSE",
           "GOAL_REGION", "WALL_X", "mirror_pose", "mirror_point", "fingertips", "touches_wall", "load_physics"]

#: The rest pose right of the wall that starts are drawn around: elbow out, fingertip at (0.68, 0.62).
REST_POSE = np.array([0.6565, 1.2635])
#: The goals right of the wall: x from, x to, y from, y to (those left of it are the mirror image).
GOAL_REGION = (0.64, 0.76, 0.60, 0.72)
#: The wall's middle: the task is mirror-symmetric about the line x = WALL_X.
WALL_X = 0.5


@dataclasses.dataclass(frozen=True)
class ObstacleParams:
    """The task's knobs (this project's choices)."""

    max_step: float = 0.4  #: largest change of each joint target per step (rad)
    control_interval: float = 0.3  #: seconds the servos track the targets per step (whole 0.01 s)
    tolerance: float = 0.08  #: the goal is reached when the fingertip is closer than this
    step_limit: int = 20  #: steps after which an episode is cut off (truncated, not terminal)
    start_spread: float = 0.2  #: start angles are uniform within +- this of the rest pose (rad)

    def __post_init__(self):
        bounds = {"max_step": (0.01, 1.0), "control_interval": (0.01, 10.0), "tolerance": (0.001, 0.5),
                  "start_spread": (0.0, 0.3)}
        for field, (low, high) in bounds.items():
            value = getattr(self, field)
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
                raise ValueError(f"{field} must be a finite number, got {value!r}")
            if not low <= value <= high:
                raise ValueError(f"{field} must be in [{low:g}, {high:g}], got {value!r}")
        if isinstance(self.step_limit, bool) or not isinstance(self.step_limit, int) or not 1 <= self.step_limit <= 1000:
            raise ValueError(f"step_limit must be a whole number in [1, 1000], got {self.step_limit!r}")


def mirror_pose(angles: np.ndarray) -> np.ndarray:
    """The pose mirrored about the wall's line: ``(theta1, theta2) -> (pi - theta1, -theta2)``."""
    angles = np.asarray(angles, dtype=np.float64)
    return np.stack([np.pi - angles[..., 0], -angles[..., 1]], axis=-1)


def mirror_point(points: np.ndarray) -> np.ndarray:
    """Points ``(..., 2)`` mirrored about the wall's line ``x = WALL_X``."""
    points = np.asarray(points, dtype=np.float64)
    return np.stack([2 * WALL_X - points[..., 0], points[..., 1]], axis=-1)




class Obstacle(TaskBase):
    """Batched multi-step episodes of ``reach2_obstacle`` (``somarm.protocols.EpisodicTask``).

    An observation is ``(theta1, theta2, goal x, goal y)``: where the arm is and where it must go.

    Args:
      params: an ``ObstacleParams``.
      n_trials, seed, trial_ids: as every batched task (trial i is the same alone or batched).
      backend: only "mujoco" (the contacts have no closed form).

    Raises:
      ValueError: another backend, or bad ``n_trials``/``trial_ids``.
    """

    name = "reach2_obstacle"
    episodic = True  #: episodes last several steps: ``step`` sets ``next_observations``/``terminal``
    has_shortest_paths = True  #: ``shortest_lengths`` searches the action box
    actuated = True  #: the servos track each step's targets for ``control_interval``

    def __init__(self, params: ObstacleParams, *, n_trials: int = 1, seed: int = 0,
                 trial_ids: np.ndarray | None = None, backend: str = "mujoco"):
        if backend != "mujoco":
            raise ValueError(f"reach2_obstacle needs the mujoco backend (contacts), got backend {backend!r}")
        self.params, self.backend, self.seed = params, backend, seed
        self.trial_ids = trial_ids_for(n_trials, trial_ids)
        self.n_trials = int(self.trial_ids.size)
        self._generators = trial_generators(seed, self.trial_ids, "task")
        x0, x1, y0, y1 = GOAL_REGION
        self.observation_low = np.array([-np.pi, -np.pi, 2 * WALL_X - x1, y0])
        self.observation_high = np.array([np.pi, np.pi, x1, y1])
        self.action_low, self.action_high = np.full(2, -params.max_step), np.full(2, params.max_step)
        # action_periodic stays TaskBase's none: the actions are angle steps, not angles.
        self.control_steps = actuation.steps_of(params.control_interval, arms.TIMESTEP)
        self._state = np.zeros((self.n_trials, 4))  # angles and goal of each trial's episode
        self._qvel = np.zeros((self.n_trials, 2))
        self._steps = np.zeros(self.n_trials, dtype=np.int64)
        self._over = np.ones(self.n_trials, dtype=bool)  # every trial starts a new episode at reset()
        self._started = False
        self.next_observations = np.zeros((self.n_trials, 4))  #: angles and goal after the last step
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

    def distances(self, angles: np.ndarray, goals: np.ndarray) -> np.ndarray:
        """Fingertip-to-goal distances ``(...)`` of joint angles ``(..., 2)`` and goals ``(..., 2)``."""
        return np.linalg.norm(fingertips(angles) - goals, axis=-1)

    def goal_of(self, observations: np.ndarray) -> np.ndarray:
        """The goal (x, y) each observation holds, ``(..., 2)``."""
        return np.asarray(observations, dtype=np.float64)[..., 2:4]

    def reward_of(self, distances: np.ndarray) -> np.ndarray:
        """The step reward ``-(1 + d)`` for distances ``d`` after the step."""
        return -(1.0 + distances)

    def episodes_from(self, rng: np.random.Generator, n: int) -> np.ndarray:
        """``n`` episodes' start poses and goals ``(n, 4)`` drawn with ``rng``.

        A side is drawn (left or right of the wall, even odds); the start is the rest pose plus uniform
        noise of +- ``start_spread`` per joint, mirrored for the left side, drawn again while a link
        overlaps the wall; the goal is uniform over ``GOAL_REGION`` on the other side.
        """
        x0, x1, y0, y1 = GOAL_REGION
        out = np.empty((int(n), 4))
        for i in range(int(n)):
            left = rng.random() < 0.5
            while True:
                pose = REST_POSE + self.params.start_spread * (2.0 * rng.random(2) - 1.0)
                pose = mirror_pose(pose) if left else pose
                if not touches_wall(pose):
                    break
            goal = np.array([x0 + (x1 - x0) * rng.random(), y0 + (y1 - y0) * rng.random()])
            out[i, :2], out[i, 2:] = pose, goal if left else mirror_point(goal)
        return out

    # -- the BatchedTask protocol --------------------------------------------------------
    def reset(self) -> np.ndarray:
        """Start new episodes in the trials whose episode is over; every trial's observation ``(n_trials, 4)``."""
        for i in np.flatnonzero(self._over):
            self._state[i] = self.episodes_from(self._generators[i], 1)[0]
            self._qvel[i] = 0.0
            self._steps[i] = 0
        self._over[:] = False
        self._started = True
        return self._state.copy()

    def step(self, actions: np.ndarray) -> np.ndarray:
        """Rewards ``(n_trials,)`` for target changes ``(n_trials, 2)``; sets the episode flags.

        Raises:
          ValueError: no ``reset`` before, or actions of the wrong shape, non-finite or out of bounds.
        """
        if not self._started:
            raise ValueError(f"{self.name}: call reset() before step()")
        actions = self.batch_actions(actions)
        self._state[:, :2], self._qvel = self.advance(self._state[:, :2], self._qvel, actions)
        self._steps += 1
        distances = self.distances(self._state[:, :2], self._state[:, 2:])
        self.terminal = distances < self.params.tolerance
        self.truncated = ~self.terminal & (self._steps >= self.params.step_limit)
        self._over = self.terminal | self.truncated
        self.next_observations = self._state.copy()
        self._started = False
        self.t += 1
        return self.reward_of(distances)

    def evaluate(self, observations: np.ndarray, actions: np.ndarray) -> np.ndarray:
        """Rewards ``(...)`` of one step from rest at the observations' angles ``(..., 4)``, towards their
        goals, with target changes ``(..., 2)``. Pure."""
        observations = np.asarray(observations, dtype=np.float64)
        if observations.ndim == 0 or observations.shape[-1] != 4 or not np.isfinite(observations).all():
            raise ValueError(f"observations must be finite with shape (..., 4), got {observations.shape}")
        actions = check_actions("actions", actions, self.action_low, self.action_high)
        shape = np.broadcast_shapes(observations.shape[:-1], actions.shape[:-1])
        state = np.broadcast_to(observations, (*shape, 4)).reshape(-1, 4)
        qpos = state[:, :2]
        moved, _ = self.advance(qpos, np.zeros_like(qpos), np.broadcast_to(actions, (*shape, 2)).reshape(-1, 2))
        return self.reward_of(self.distances(moved, state[:, 2:])).reshape(shape)

    def sample_observations(self, rng: np.random.Generator, n: int) -> np.ndarray:
        """``n`` start observations (start pose and goal) ``(n, 4)`` drawn with ``rng``."""
        return self.episodes_from(rng, n)

    def sample_starts(self, rng: np.random.Generator, n: int) -> np.ndarray:
        """``n`` episode starts for ``run_episodes``: start observations (pose and goal) ``(n, 4)``."""
        return self.episodes_from(rng, n)

    # -- whole episodes --------------------------------------------------------------------
    def run_episodes(self, policy, starts: np.ndarray, *, paths: bool = False) -> dict[str, np.ndarray]:
        """Run episodes from ``starts`` ``(m, 4)`` (start angles and goal) to the goal or the step limit,
        all in one batch.

        Args:
          policy: maps observations ``(m, 4)`` to target changes ``(m, 2)`` (called once per step).
          starts: start observations, one episode each.
          paths: also return every timestep's angles.

        Returns:
          ``{"success": (m,) bool, "length": (m,) steps taken, "returns": (m,) undiscounted}`` and with
          ``paths`` ``"path": (m, 1 + step_limit * control_steps, 2)`` (held at the last pose once done).
        """
        state = np.array(starts, dtype=np.float64).reshape(-1, 4)
        qpos, goals = state[:, :2].copy(), state[:, 2:]
        m = len(qpos)
        qvel = np.zeros_like(qpos)
        running = np.ones(m, dtype=bool)
        length = np.zeros(m, dtype=np.int64)
        success = np.zeros(m, dtype=bool)
        returns = np.zeros(m)
        trace = [qpos[:, None, :].copy()] if paths else None
        for _ in range(self.params.step_limit):
            observed = np.column_stack([qpos, goals])
            actions = np.clip(np.asarray(policy(observed), dtype=np.float64), self.action_low, self.action_high)
            steps, new_v = self.advance(qpos, qvel, actions, path=paths)
            new_q = steps[:, -1] if paths else steps
            if paths:
                trace.append(np.where(running[:, None, None], steps, qpos[:, None, :]))
            distances = self.distances(new_q, goals)
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


    def shortest_lengths(self, starts: np.ndarray) -> np.ndarray:
        """The fewest steps from each start ``(m, 4)`` to its goal, by ``obstacle_search.shortest_paths``
        (a search over a fine grid of the action box, checked by replay), ``(m,)``."""
        from somarm.tasks import obstacle_search

        return obstacle_search.shortest_paths(self, starts)["length"]


class ObstaclePhysics(arms.ArmPhysics):
    """dm_control physics of ``models/arm2_obstacle.xml``: the arm, the wall and the goal marker."""

    def wall_penetration(self) -> float:
        """The deepest overlap of a link with the wall now (0 if they do not touch)."""
        depths = [-self.data.contact[k].dist for k in range(self.data.ncon)]
        return max([0.0, *depths])


def load_physics() -> ObstaclePhysics:
    """The dm_control physics of ``models/arm2_obstacle.xml``."""
    return ObstaclePhysics.from_xml_path(str(model_path("arm2_obstacle")))


class ObstacleEnvTask(control.Task):
    """dm_env side of ``reach2_obstacle``: one dm_env episode is one episode of trial 0 of a batch.

    The start pose and goal of episode k are those trial 0 of a batch with the same seed starts its
    k-th episode with; the goal marker moves there. The environment steps ``control_steps``
    timesteps per action (``n_sub_steps``), ends the episode at the goal with discount 0, and cuts
    it at the step limit with discount 1. The observation is ``angles`` and ``goal``.
    """

    def __init__(self, batched: Obstacle):
        self.batched = batched
        self._steps = 0
        self._goal = np.zeros(2)
        self.sub_steps = batched.control_steps  #: timesteps per dm_env step (``tasks.load`` reads it)

    def initialize_episode(self, physics: ObstaclePhysics) -> None:
        self.batched._over[:] = True  # a new episode whatever state the batch was left in
        start = self.batched.reset()[0]
        self._goal = start[2:].copy()
        physics.set_goal(self._goal)
        physics.set_angles(start[:2])
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
        low, high = self.batched.observation_low, self.batched.observation_high
        return OrderedDict({"angles": specs.BoundedArray((2,), np.float64, low[:2], high[:2], name="angles"),
                            "goal": specs.BoundedArray((2,), np.float64, low[2:], high[2:], name="goal")})

    def get_observation(self, physics: ObstaclePhysics):
        return OrderedDict({"angles": physics.angles(), "goal": self._goal.copy()})

    def _distance(self, physics: ObstaclePhysics) -> float:
        return float(np.linalg.norm(physics.fingertip() - self._goal))

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
        summary="actuated 2-link arm steps around a wall to a goal behind it (multi-step, delayed reward); "
                "obs 2 angles and the goal (x, y), action 2 target changes",
        params=ObstacleParams,
        settable=("max_step", "control_interval", "tolerance", "step_limit", "start_spread"),
        make=lambda params, **kwargs: Obstacle(params, **kwargs),
        environment=lambda batched: (load_physics(), ObstacleEnvTask(batched)),
        preset="obstacle",
        n_steps=500_000,
        model="arm2_obstacle",
        observation_labels=("theta1 (rad)", "theta2 (rad)", "goal x", "goal y"),
        action_labels=("change of theta1's target (normalised)", "change of theta2's target (normalised)"),
        backends=("mujoco",),
        episodic=Obstacle.episodic,  # the class owns the fact; the record lists it without building a task
    ),
)
