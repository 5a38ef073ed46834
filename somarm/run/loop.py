"""The training loop: one task, one or more learners in lockstep, one physics call per step.

Data flows one way each step: ``task.reset() -> observations -> learner.act -> actions ->
task.step (physics) -> rewards -> learner.learn``. The loop holds both ends and passes arrays.
A multi-step task (``task.episodic``) also hands the learner each trial's next observation and
whether its episode ended at the goal; its ``reset()`` restarts only the finished episodes.
The loop composes three parts: ``run.stepper`` (one step of every task and learner),
``run.recorder`` (the learning curves and episodes) and ``run.snapshots`` (maps copied mid-run).
Building the task and learners, and writing the results, belong to ``somarm.run``.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from somarm.protocols import BatchedTask, Learner
from somarm.run.episodes import EpisodeLog, Episodes
from somarm.run.progress import Progress
from somarm.run.recorder import RECENT_EPISODES, BlockRecorder
from somarm.run.snapshots import Snapshots, snapshot
from somarm.run.stepper import Stepper
from somarm.run.stopping import stop_between_steps

__all__ = ["Curves", "EpisodeLog", "Episodes", "StepHook", "loop", "snapshot", "final_blocks", "final_rewards",
           "RECENT_EPISODES"]

StepHook = Callable[[int, np.ndarray, np.ndarray, np.ndarray], None]


@dataclass
class Curves:
    """What ``loop`` returns, for all trials of all learners side by side."""

    block_means: np.ndarray  #: (n_blocks, n_trials) mean reward of each complete block
    block_sq_means: np.ndarray  #: (n_blocks, n_trials) mean squared reward of each block (data spread)
    steps_done: int
    wall_time: float
    interrupted: bool = False
    snapshots: list[dict[int, dict[str, np.ndarray]]] = field(default_factory=list)
    """Per learner: copies of its maps (and Q) after each step asked for."""
    episodes: Episodes | None = None
    """Every finished training episode of the multi-step tasks (None: one-step tasks only)."""
    failed: str | None = None
    """Why training stopped early where a task failed (it raised, or gave a non-finite observation):
    one line; ``interrupted`` is then True and the curves hold the steps before it."""


def loop(
    task: BatchedTask | list[BatchedTask],
    learners: list[Learner],
    parts: list[slice],
    *,
    n_steps: int,
    block: int,
    owners: list[int] | None = None,
    progress: bool = True,
    on_step: StepHook | None = None,
    label: str = "",
    snapshots_at: tuple[int, ...] = (),
    episode_log: EpisodeLog | None = None,
    keep_failed: bool = False,
) -> Curves:
    """Train ``learners`` (learner i owns trials ``parts[i]`` of its task) for ``n_steps`` steps.

    Each step the ``Stepper`` steps every task and learner, the ``BlockRecorder`` adds the rewards to
    the learning curves, ``on_step`` sees the step, and ``Snapshots`` copies the maps at the steps
    asked for. Ctrl-C, SIGTERM or SIGHUP stops at the end of the current step (``interrupted=True``); an
    ``on_step`` hook that raises ``KeyboardInterrupt`` stops the same way. A step that fails (a task
    raises, or gives a non-finite observation) raises, or with ``keep_failed`` stops there too, with
    ``failed`` saying why.

    Args:
      task: the batched task of all trials, or several tasks stepped together each step (one
        physics call where they allow it: ``tasks.base.step_together``).
      learners: the learners, acting on their slices of their task's observations.
      parts: learner i's trials, ``slice``s covering ``range(n_trials)`` of each task.
      n_steps: steps to take. block: steps per recorded point of the learning curves.
      owners: the index of each learner's task (default: all the first).
      progress: draw a progress bar on stderr: the mean reward of the last block for one-step tasks,
        the mean return of the last ``RECENT_EPISODES`` finished episodes for episodic ones (each
        scale of reward apart, named).
      on_step: called as ``on_step(step, observations, actions, rewards)`` after every step; cheap
        (one task only).
      label: progress-bar label.
      snapshots_at: steps after which to copy each learner's maps.
      episode_log: the log of the tasks' training episodes to go on with (one made here by default);
        the curves' ``episodes`` are those that ended in this call, at this call's steps.
      keep_failed: a failed step ends the loop with ``failed`` set (the steps before it kept); by
        default its exception is raised.

    Returns:
      The ``Curves`` of every trial, the tasks' trials side by side in task order.

    Raises:
      ValueError: ``on_step`` with several tasks.
    """
    tasks = task if isinstance(task, list) else [task]
    owners = [0] * len(learners) if owners is None else owners
    if len(tasks) > 1 and on_step is not None:
        raise ValueError("on_step needs a group on one task and seed")
    stepper = Stepper(tasks, learners, parts, owners)
    recorder = BlockRecorder(tasks, n_steps=n_steps, block=block, episode_log=episode_log)
    snapshots = Snapshots(learners, snapshots_at)
    bar = Progress(n_steps, label=label, enabled=progress)
    start = time.perf_counter()
    step = 0
    interrupted = False
    failed = None
    with stop_between_steps() as stop:
        try:
            while step < n_steps:
                try:
                    rewards = stepper.step()
                except Exception as exc:  # the task's (an environment's) failure: keep the steps before it
                    if not keep_failed:
                        raise
                    failed, interrupted = _failure(step + 1, exc), True
                    break
                step += 1
                if recorder.record(rewards):
                    bar.update(step, recorder.measures)
                if on_step is not None:
                    on_step(step, stepper.observations[0], stepper.actions[0], rewards)
                snapshots.after(step)
                if stop["requested"]:
                    interrupted = True
                    break
        except KeyboardInterrupt:  # raised by an on_step hook, or outside the main thread
            interrupted = True
    wall_time = time.perf_counter() - start
    bar.close(step, recorder.measures)
    block_means, block_sq_means, episodes = recorder.curves()
    return Curves(block_means, block_sq_means, step, wall_time, interrupted, snapshots.taken, episodes, failed)


def _failure(step: int, exc: Exception) -> str:
    """A failed step in one line: ``training failed at step 31: ValueError: its message's first line``."""
    said = (str(exc).strip().splitlines() or [""])[0][:300]
    return f"training failed at step {step}: {type(exc).__name__}" + (f": {said}" if said else "")


def final_blocks(n_blocks: int, block: int, window: int) -> int:
    """How many of the last blocks make up a final window of about ``window`` steps (0 if none)."""
    return min(n_blocks, max(1, round(window / block)))


def final_rewards(block_means: np.ndarray, block: int, window: int) -> np.ndarray:
    """Each trial's mean reward over the last ``window`` steps (whole blocks), shape ``(n_trials,)``.

    NaN when no block is complete.
    """
    n = final_blocks(len(block_means), block, window)
    if n == 0:
        return np.full(block_means.shape[1], np.nan)
    return block_means[-n:].mean(axis=0)
