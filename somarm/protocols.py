"""The two contracts data flows through: task -> observation -> learner -> action -> task.

A learner never sees a task and a task never sees a learner; the experiment runner, the
evaluation and the viewer hold one of each and pass arrays between them. What they rely on is
declared here, so none of them asks an object whether it happens to have an attribute: a task
says whether its episodes last several steps (``episodic``; then it is an ``EpisodicTask``), a
learner says whether it has maps to draw (``has_maps``, ``has_action_map``).
"""

from __future__ import annotations

from typing import Protocol, runtime_checkable

import numpy as np

__all__ = ["Learner", "BatchedTask", "EpisodicTask"]


@runtime_checkable
class Learner(Protocol):
    """What every learner (SOM-Q, Motoric Map, tabular) offers, batched over independent trials."""

    kind: str  #: the registry's name of the learner's kind (``somarm.learners.LEARNERS``)
    n_trials: int
    t: int  #: steps learned so far (the t of the annealing schedules)
    #: An input SOM ``input_weights (n_trials, n_input_units, obs_dim)`` with an action per unit,
    #: ``action_weights (n_trials, n_units, action_dim)``; False for a learner on fixed grids.
    has_maps: bool
    #: The action units are a map of their own joined to the input units by ``q (n_trials,
    #: n_input_units, n_action_units)`` (SOM-Q); False where each input unit keeps its own action.
    has_action_map: bool
    learned_arrays: tuple[str, ...]  #: names of the arrays that show what has been learned
    periodic_dimensions: np.ndarray  #: (action_dim,) bools: the action dimensions it wraps round

    def act(self, observations: np.ndarray) -> np.ndarray:
        """Exploring action for each trial: ``(n_trials, obs_dim) -> (n_trials, action_dim)``."""

    def learn(
        self,
        rewards: np.ndarray,
        next_observations: np.ndarray | None = None,
        terminal: bool | np.ndarray = True,
    ) -> None:
        """Learn from the rewards ``(n_trials,)`` that followed the last ``act``."""

    def predict(self, observations: np.ndarray) -> np.ndarray:
        """Greedy actions, no exploration, no learning.

        ``(n_trials, obs_dim) -> (n_trials, action_dim)`` or
        ``(n_trials, n_obs, obs_dim) -> (n_trials, n_obs, action_dim)``.
        """

    def save(self, path) -> None:
        """Write the whole state (config, maps, values, step, random streams) atomically."""


@runtime_checkable
class BatchedTask(Protocol):
    """A task evaluated for ``n_trials`` independent trials in one call.

    Episodes are one step long unless ``episodic``: then the task is an ``EpisodicTask``, and
    after each ``step`` says where every trial is and whether its episode ended there.
    """

    name: str
    n_trials: int
    t: int  #: steps taken (the learner's t; a task whose goals move reads its phase from it)
    episodic: bool  #: episodes last several steps (an ``EpisodicTask``); False: one step each
    has_shortest_paths: bool  #: an episodic task that finds each episode's shortest path (``shortest_lengths``)
    #: The joints are driven by servos: an action is a target they track over time (a one-step
    #: actuated task offers ``reached_angles(actions, path=True)``, the joints' path to the reward).
    actuated: bool
    observation_low: np.ndarray  #: (obs_dim,)
    observation_high: np.ndarray  #: (obs_dim,)
    action_low: np.ndarray  #: (action_dim,)
    action_high: np.ndarray  #: (action_dim,)
    action_periodic: np.ndarray  #: (action_dim,) bools: angles whose low and high are one pose

    def set_step(self, t: int) -> None:
        """Move the step counter to ``t`` (e.g. a trained learner's, to evaluate in its phase)."""

    def reset(self) -> np.ndarray:
        """Start a new episode in every trial whose episode is over (one-step tasks: every trial);
        returns every trial's observation ``(n_trials, obs_dim)``."""

    def step(self, actions: np.ndarray) -> np.ndarray:
        """Apply ``(n_trials, action_dim)`` actions; returns rewards ``(n_trials,)``."""

    def evaluate(self, observations: np.ndarray, actions: np.ndarray) -> np.ndarray:
        """Rewards for given observations and actions, ``(..., obs_dim), (..., action_dim) -> (...)``.

        Deterministic and stateless: no episode counter moves, no random number is drawn.
        """

    def sample_observations(self, rng: np.random.Generator, n: int) -> np.ndarray:
        """``n`` fresh observations from the task's distribution, shape ``(n, obs_dim)``."""


@runtime_checkable
class EpisodicTask(BatchedTask, Protocol):
    """A task whose episodes last several steps and end at different steps in different trials.

    The batch never waits: ``reset`` restarts only the trials whose episode is over, and after
    each ``step`` the flags below say what happened in each trial.
    """

    next_observations: np.ndarray  #: (n_trials, obs_dim): where each trial is after the last step
    terminal: np.ndarray  #: (n_trials,) bools: the last step ended the episode (at the goal; a Gymnasium "terminated")
    truncated: np.ndarray  #: (n_trials,) bools: the last step hit the step limit (not terminal)

    def sample_starts(self, rng: np.random.Generator, n: int) -> np.ndarray:
        """``n`` episode starts drawn with ``rng``, in the form ``run_episodes`` takes (start poses
        ``(n, obs_dim)``, or a Gymnasium environment's reset seeds ``(n,)``)."""

    def goal_of(self, observations: np.ndarray) -> np.ndarray:
        """The goal each observation ``(..., obs_dim)`` reaches for, e.g. the fingertip's (x, y): ``(..., 2)``."""

    def run_episodes(self, policy, starts: np.ndarray, *, paths: bool = False) -> dict[str, np.ndarray]:
        """Whole episodes of ``policy`` (observations ``(m, obs_dim)`` -> actions ``(m, action_dim)``)
        from ``starts`` ``(m, obs_dim)``, all in one batch.

        Returns ``{"length": (m,) steps, "returns": (m,)}`` and, for a task with a goal, ``"success":
        (m,) bools``; with ``paths`` also ``"path"``: the state (joint angles, observations) of every timestep.
        """

    def shortest_lengths(self, starts: np.ndarray) -> np.ndarray:
        """The fewest steps from each start ``(m, obs_dim)`` to its goal, ``(m,)``: the yardstick of a
        greedy episode's length, found by a search over the actions and checked by replaying its path
        through ``run_episodes`` (the step limit where the search finds none)."""
