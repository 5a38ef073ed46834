"""Training a run: one config, or several in lockstep (``RunGroup``), into ``RunResult``s."""

from __future__ import annotations

import json
from dataclasses import dataclass, field

import numpy as np

from somarm.protocols import BatchedTask, Learner
from somarm.run.build import check_memory_needs, make_learner, make_task
from somarm.run.config import RunConfig
from somarm.run.loop import Episodes, StepHook, loop

__all__ = ["RunResult", "RunFailed", "train", "train_group", "share_lanes", "RunGroup"]


@dataclass
class RunResult:
    """What ``train`` returns: the trained learner and its learning curves."""

    config: RunConfig
    learner: Learner
    task: BatchedTask
    block_means: np.ndarray  #: (n_blocks, n_trials) mean reward of each complete block
    block_sq_means: np.ndarray  #: (n_blocks, n_trials) mean squared reward of each block (data spread)
    steps_done: int
    wall_time: float
    interrupted: bool = False
    snapshots: dict[int, dict[str, np.ndarray]] = field(default_factory=dict)
    """Copies of the maps (and Q) of every trial taken after the steps asked for in ``train``."""
    episodes: Episodes | None = None
    """The training episodes that ended (a multi-step task's; None for one-step tasks)."""
    failed: str | None = None
    """Why training stopped early where the task failed (it raised, or gave a non-finite observation),
    in one line; ``interrupted`` is then True, and the run holds the steps before the failure."""

    @property
    def block_returns(self) -> np.ndarray | None:
        """Mean return of the training episodes that ended in each block, ``(n_blocks, n_trials)``
        (NaN where none ended); None for a one-step task."""
        if self.episodes is None:
            return None
        return self.episodes.block_returns(len(self.block_means), self.config.block, self.config.n_trials)

    @property
    def steps(self) -> np.ndarray:
        """Step at the end of each recorded block, shape ``(n_blocks,)``."""
        return (np.arange(len(self.block_means)) + 1) * self.config.block


def train(config: RunConfig, *, progress: bool = True, on_step: StepHook | None = None,
          label: str | None = None, snapshots_at: tuple[int, ...] = ()) -> RunResult:
    """Train ``config.n_trials`` trials for ``config.n_steps`` steps.

    Ctrl-C or SIGTERM stops at the end of the current step and returns what was learned so far
    (``interrupted=True``): the caller can still write a valid partial run.

    Args:
      config: the run (defaults are filled in here).
      progress: draw a progress bar with the running mean reward on stderr.
      on_step: called as ``on_step(step, observations, actions, rewards)`` after every step
        (the live viewer); it must be cheap.
      label: progress-bar label (default ``task/learner``).
      snapshots_at: steps after which to copy the maps (``RunResult.snapshots``).

    Returns:
      A ``RunResult``.

    Raises:
      ValueError: a bad setting (before anything is trained).
      RunFailed: the task failed mid-run (a ValueError holding the partial result).
    """
    return train_group([config], progress=progress, on_step=on_step, label=label, snapshots_at=snapshots_at)[0]


def train_group(configs: list[RunConfig], *, progress: bool = True, on_step: StepHook | None = None,
                label: str | None = None, snapshots_at: tuple[int, ...] = ()) -> list[RunResult]:
    """Train several learners in lockstep, with one physics call per step for all (``RunGroup``).

    The configs share backend, steps and block; those of one task, task parameters and seed share
    one batched task. Each config's trials see the same observations and random numbers as when
    trained alone, so results equal ``train``'s. Comparisons (Figs. 13, 21-24), Fig. 25's four
    experiments and ``reproduce --seeds`` run this way: the physics dominates their cost.

    Returns:
      One ``RunResult`` per config, in order. ``on_step`` sees the whole group's arrays (one task).

    Raises:
      RunFailed: the task failed mid-run (a ValueError holding the partial results).
    """
    results = RunGroup(configs).train(progress=progress, on_step=on_step, label=label, snapshots_at=snapshots_at)
    if results[0].failed is not None:
        raise RunFailed(results)
    return results


class RunFailed(ValueError):
    """Training stopped because the task failed (``RunResult.failed`` is the message); ``results`` holds
    the runs up to the failure, which a caller may still write (``run.write`` marks them failed)."""

    def __init__(self, results: list[RunResult]) -> None:
        super().__init__(results[0].failed)
        self.results = results

    def __reduce__(self):  # sent to another process as its message alone
        return ValueError, (str(self),)


def share_lanes(trials: list[int], lanes: int) -> list[int]:
    """The lane (a process of ``run.split``) of each config of a lockstep group: the most trials first,
    each to the lane with the fewest so far (ties to the lowest lane). With one lane, or one config,
    all in lane 0.
    """
    load = [0] * max(1, min(lanes, len(trials)))
    lane_of = [0] * len(trials)
    for j in sorted(range(len(trials)), key=lambda j: -trials[j]):
        k = load.index(min(load))
        lane_of[j] = k
        load[k] += trials[j]
    return lane_of


class RunGroup:
    """Configs trained in lockstep, resolved and built once: a task per task, task parameters and
    seed (shared by the configs that share those), one learner each.

    Configs of one task differ only in their learner settings (learner, preset, overrides, trials)
    and share one batched task; configs of different tasks or seeds (Fig. 25's experiments A-D,
    ``reproduce --seeds``) get a task each, stepped together with one physics call where the tasks
    allow it (``tasks.base.step_together``: several throw tasks fly in one batch). Building is
    where a bad preset, ``--set`` or ``--task-set`` fails, so a caller can build first (fail fast),
    then prepare its output, then ``train`` what it built.

    A trial's arithmetic does not depend on the group it is in, so the results equal separate runs.

    Args:
      configs: the configs of the group.

    Raises:
      ValueError: a bad setting, or configs that do not share backend, steps and block.
    """

    def __init__(self, configs: list[RunConfig]) -> None:
        self.configs = [c.resolved() for c in configs]
        if len({(c.backend, c.n_steps, c.block) for c in self.configs}) != 1:
            raise ValueError("a group shares backend, steps and block; these differ")
        check_memory_needs(self.configs)
        keys = [(c.task, json.dumps(c.task_params, sort_keys=True), c.seed) for c in self.configs]
        distinct = list(dict.fromkeys(keys))
        self.tasks = []
        for key in distinct:
            members = [c for c, k in zip(self.configs, keys, strict=True) if k == key]
            self.tasks.append(make_task(members[0], np.concatenate([c.trial_ids_array() for c in members])))
        self.task = self.tasks[0]
        # Each config owns a slice of its task's trials and a slice of the curves' columns.
        self.owners, self.parts, self.columns = [], [], []
        offsets = np.cumsum([0] + [t.n_trials for t in self.tasks])
        filled = [0] * len(self.tasks)
        for key, config in zip(keys, self.configs, strict=True):
            i = distinct.index(key)
            self.owners.append(i)
            self.parts.append(slice(filled[i], filled[i] + config.n_trials))
            self.columns.append(slice(int(offsets[i]) + filled[i], int(offsets[i]) + filled[i] + config.n_trials))
            filled[i] += config.n_trials
        self.learners = [make_learner(c, self.tasks[i]) for c, i in zip(self.configs, self.owners, strict=True)]

    def train(self, *, progress: bool = True, on_step: StepHook | None = None, label: str | None = None,
              snapshots_at: tuple[int, ...] = ()) -> list[RunResult]:
        """Train the built learners once (see ``train_group``); one ``RunResult`` per config.

        A task that fails (raises, or gives a non-finite observation) stops the training there: the
        results hold the steps before it, ``interrupted`` and ``failed`` (the error's one line) set,
        for the caller to write (``run.write_claimed`` keeps them, marked failed, and then raises).

        Raises:
          ValueError: ``on_step`` for a group of several tasks or seeds.
        """
        first = self.configs[0]
        curves = loop(self.tasks, self.learners, self.parts, owners=self.owners, n_steps=first.n_steps,
                      block=first.block, progress=progress, on_step=on_step,
                      label=label or f"{first.task}/{first.learner}", snapshots_at=snapshots_at, keep_failed=True)
        results = []
        for config, learner, column, taken in zip(self.configs, self.learners, self.columns, curves.snapshots,
                                                  strict=True):
            own_task = self.task if len(self.configs) == 1 else make_task(config)
            own_task.set_step(curves.steps_done)  # its phase (four_goals) is the one the learner reached
            results.append(RunResult(
                config=config,
                learner=learner,
                task=own_task,
                block_means=curves.block_means[:, column].copy(),
                block_sq_means=curves.block_sq_means[:, column].copy(),
                steps_done=curves.steps_done,
                wall_time=curves.wall_time,
                interrupted=curves.interrupted,
                snapshots=taken,
                episodes=None if curves.episodes is None or not own_task.episodic else curves.episodes.of(column),
                failed=curves.failed,
            ))
        return results
