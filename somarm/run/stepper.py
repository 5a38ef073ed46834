"""One training step of tasks and learners in lockstep: reset, act, one physics call, learn.

Everything steps in the calling thread; the physics of a step is one batched call, which uses the
batch's own threads (``tasks.threads()``). Stepping groups of learners in threads side by side did
not pay: ``somarm.perf.loop`` measured it no faster than one thread on the reproduction's groups.
"""

from __future__ import annotations

from typing import cast

import numpy as np

from somarm.protocols import BatchedTask, EpisodicTask, Learner
from somarm.tasks.base import step_together

__all__ = ["Stepper"]


class Stepper:
    """Steps ``tasks`` and ``learners`` (learner j owns trials ``parts[j]`` of task ``owners[j]``).

    ``step()`` takes one step of everything and returns the rewards of all trials side by side,
    ``(n_trials,)``; ``observations``, ``actions`` and ``rewards`` hold each task's arrays of that step.
    An observation that is not finite raises ``FloatingPointError`` before a learner sees it.

    Args:
      tasks: the batched tasks, stepped together each step (one physics call where they allow it:
        ``tasks.base.step_together``).
      learners: the learners, acting on their slices of their task's observations.
      parts: learner j's trials, ``slice``s covering ``range(n_trials)`` of each task.
      owners: the index of each learner's task.
    """

    def __init__(self, tasks: list[BatchedTask], learners: list[Learner], parts: list[slice],
                 owners: list[int]) -> None:
        self.tasks, self.learners, self.parts, self.owners = tasks, learners, parts, owners
        self.episodic = [t.episodic for t in tasks]
        self.actions = [np.empty((t.n_trials, t.action_low.size)) for t in tasks]
        self.observations: list[np.ndarray] = [np.empty(0)] * len(tasks)
        self.rewards: list[np.ndarray] = [np.empty(0)] * len(tasks)

    def step(self) -> np.ndarray:
        """One step of every task and learner: reset, act, one physics call, learn; the rewards of
        all trials side by side, ``(n_trials,)``."""
        tasks, learners, owners, parts = self.tasks, self.learners, self.owners, self.parts
        for i, task in enumerate(tasks):
            self.observations[i] = _finite(task.reset(), "observation")
        for j, learner in enumerate(learners):
            i, part = owners[j], parts[j]
            self.actions[i][part] = learner.act(self.observations[i][part])
        self.rewards[:] = step_together(tasks, self.actions)
        for j, learner in enumerate(learners):
            i, part = owners[j], parts[j]
            if self.episodic[i]:  # the next state and whether the episode ended there
                done = cast(EpisodicTask, tasks[i])
                learner.learn(self.rewards[i][part], _finite(done.next_observations[part], "next observation"),
                              done.terminal[part])
            else:
                learner.learn(self.rewards[i][part])
        return self.rewards[0] if len(tasks) == 1 else np.concatenate(self.rewards)


def _finite(observations: np.ndarray, what: str) -> np.ndarray:
    """``observations`` if every value is finite; a learner fed NaN learns NaN from then on.

    Raises:
      FloatingPointError: naming the first trial whose observation is not finite.
    """
    if not np.isfinite(observations).all():
        trial = int(np.flatnonzero(~np.isfinite(observations).reshape(len(observations), -1).all(axis=1))[0])
        raise FloatingPointError(f"the task's {what} of trial {trial} is not finite "
                                 f"({np.asarray(observations[trial]).ravel()[:4].tolist()})")
    return observations
