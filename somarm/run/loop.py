"""The training loop: one task, one or more learners in lockstep, one physics call per step.

Data flows one way each step: ``task.reset() -> observations -> learner.act -> actions ->
task.step (physics) -> rewards -> learner.learn``. The loop holds both ends and passes arrays.
A multi-step task (``task.episodic``) also hands the learner each trial's next observation and
whether its episode ended at the goal; its ``reset()`` restarts only the finished episodes.
Building the task and learners, and writing the results, belong to ``somarm.run``.
"""

from __future__ import annotations

import contextlib
import time
from collections import deque
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from typing import cast

import numpy as np

from somarm.protocols import BatchedTask, EpisodicTask, Learner
from somarm.run.progress import Measures, Progress
from somarm.run.stopping import stop_between_steps
from somarm.tasks.base import step_together
from somarm.tasks.pool import single_threaded

__all__ = ["Curves", "EpisodeLog", "Episodes", "StepHook", "loop", "snapshot", "final_blocks", "final_rewards",
           "RECENT_EPISODES"]

#: The progress bar of an episodic task shows the mean return of this many last finished episodes
#: (as Stable-Baselines3's ``ep_rew_mean`` does), fewer until that many have ended.
RECENT_EPISODES = 100

StepHook = Callable[[int, np.ndarray, np.ndarray, np.ndarray], None]


def snapshot(learner: Learner) -> dict[str, np.ndarray]:
    """Copies of the arrays that show what a learner has learned (its ``learned_arrays``), for figures mid-run."""
    return {name: np.array(getattr(learner, name)) for name in learner.learned_arrays}


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


@dataclass
class Episodes:
    """The training episodes that ended, in the order they ended: one entry each."""

    ends: np.ndarray  #: (k,) the step (1-based) at which the episode ended
    trials: np.ndarray  #: (k,) the curves' column (trial) it belongs to
    returns: np.ndarray  #: (k,) its undiscounted return
    lengths: np.ndarray  #: (k,) its steps

    def of(self, columns: slice) -> Episodes:
        """The episodes of the trials in ``columns``, renumbered from 0."""
        keep = (self.trials >= columns.start) & (self.trials < columns.stop)
        return Episodes(self.ends[keep], self.trials[keep] - columns.start, self.returns[keep], self.lengths[keep])

    def block_returns(self, n_blocks: int, block: int, n_trials: int) -> np.ndarray:
        """Mean return of the episodes that ended in each block, per trial, ``(n_blocks, n_trials)``;
        NaN where none ended."""
        total = np.zeros((n_blocks, n_trials))
        count = np.zeros((n_blocks, n_trials))
        index = (self.ends - 1) // block
        keep = index < n_blocks
        np.add.at(total, (index[keep], self.trials[keep]), self.returns[keep])
        np.add.at(count, (index[keep], self.trials[keep]), 1)
        with np.errstate(invalid="ignore", divide="ignore"):
            return np.where(count > 0, total / np.maximum(count, 1), np.nan)


class EpisodeLog:
    """Collects the training episodes of the multi-step tasks as they end (``Episodes``).

    It holds each trial's running return and length, so one log passed to several ``loop`` calls
    on the same tasks (``SOMQ.learn`` called again) counts an episode that spans two calls whole.
    """

    def __init__(self, tasks: list[BatchedTask]) -> None:
        self.tasks = tasks
        self.offsets = np.cumsum([0] + [t.n_trials for t in tasks])
        self.returns = np.zeros(int(self.offsets[-1]))
        self.lengths = np.zeros(int(self.offsets[-1]), dtype=np.int64)
        self.ended: list[tuple[int, np.ndarray, np.ndarray, np.ndarray]] = []

    def record(self, step: int, rewards: np.ndarray) -> None:
        """Add a step's rewards (all trials side by side) and close the episodes that ended there."""
        self.returns += rewards
        self.lengths += 1
        for k, task in enumerate(self.tasks):
            if not task.episodic:
                continue
            done = cast(EpisodicTask, task)
            over = np.flatnonzero(done.terminal | done.truncated) + self.offsets[k]
            if over.size:
                self.ended.append((step, over, self.returns[over].copy(), self.lengths[over].copy()))
                self.returns[over] = 0.0
                self.lengths[over] = 0

    def take(self) -> Episodes:
        """The episodes that ended since the last ``take`` (their steps as ``record`` was given them)."""
        ended, self.ended = self.ended, []
        return self._episodes(ended)

    @staticmethod
    def _episodes(ended: list[tuple[int, np.ndarray, np.ndarray, np.ndarray]]) -> Episodes:
        if not ended:
            empty = np.zeros(0)
            return Episodes(empty.astype(np.int64), empty.astype(np.int64), empty, empty.astype(np.int64))
        return Episodes(np.concatenate([np.full(len(o), s) for s, o, _, _ in ended]).astype(np.int64),
                        np.concatenate([o for _, o, _, _ in ended]).astype(np.int64),
                        np.concatenate([r for _, _, r, _ in ended]),
                        np.concatenate([n for _, _, _, n in ended]).astype(np.int64))


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
    lanes: list[list[int]] | None = None,
    episode_log: EpisodeLog | None = None,
) -> Curves:
    """Train ``learners`` (learner i owns trials ``parts[i]`` of its task) for ``n_steps`` steps.

    Ctrl-C or SIGTERM stops at the end of the current step (``interrupted=True``); an
    ``on_step`` hook that raises ``KeyboardInterrupt`` stops the same way.

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
      lanes: the tasks (indices) each thread steps, with their learners, side by side (default one
        lane of every task, in this thread); with several, each step runs either in the lanes or in
        this thread alone, whichever measures faster (``_LanePolicy``).
      episode_log: the log of the tasks' training episodes to go on with (one made here by default);
        the curves' ``episodes`` are those that ended in this call, at this call's steps.

    Returns:
      The ``Curves`` of every trial, the tasks' trials side by side in task order.

    Raises:
      ValueError: ``on_step`` with several tasks.
    """
    tasks = task if isinstance(task, list) else [task]
    owners = [0] * len(learners) if owners is None else owners
    if len(tasks) > 1 and on_step is not None:
        raise ValueError("on_step needs a group on one task and seed")
    lanes = [list(range(len(tasks)))] if lanes is None else lanes
    if sorted(i for lane in lanes for i in lane) != list(range(len(tasks))):
        raise ValueError("lanes must share out the tasks, each task to one lane")
    n_trials = sum(t.n_trials for t in tasks)
    n_blocks = n_steps // block
    block_means = np.zeros((n_blocks, n_trials))
    block_sq_means = np.zeros((n_blocks, n_trials))
    accumulated = np.zeros(n_trials)
    accumulated_sq = np.zeros(n_trials)
    actions = [np.empty((t.n_trials, t.action_low.size)) for t in tasks]
    snapshots: list[dict[int, dict[str, np.ndarray]]] = [{} for _ in learners]
    bar = Progress(n_steps, label=label, enabled=progress)
    episodic = [t.episodic for t in tasks]  # multi-step episodes (reach2_obstacle, gym:ID): EpisodicTasks
    log = episode_log if episode_log is not None else (EpisodeLog(tasks) if any(episodic) else None)
    # The bar shows each scale of reward apart: one-step tasks' mean reward, episodic tasks' mean return.
    one_step = np.concatenate([np.full(t.n_trials, not e) for t, e in zip(tasks, episodic, strict=True)])
    recent: deque[float] = deque(maxlen=RECENT_EPISODES)
    seen = 0 if log is None else len(log.ended)  # episodes the log already held when this call began
    shown: Measures = _measures(None, one_step, recent, any(episodic))
    # The lanes other than the first run in their own threads; each owns its tasks and learners,
    # so every trial sees the same arithmetic in the same order as with one lane. Whether a step
    # is faster in lanes or in this thread alone (all tasks, one physics call on the batch's own
    # threads) depends on the machine and on how the learners' cost changes: ``_LanePolicy`` measures.
    pool = ThreadPoolExecutor(len(lanes) - 1, thread_name_prefix="somarm-lane") if len(lanes) > 1 else None
    policy = _LanePolicy(enabled=pool is not None)
    members = [[j for j, i in enumerate(owners) if i in lane] for lane in lanes]
    every_task, every_learner = list(range(len(tasks))), list(range(len(learners)))
    observations: list[np.ndarray] = [np.empty(0)] * len(tasks)
    rewards_of: list[np.ndarray] = [np.empty(0)] * len(tasks)

    def run_lane(task_ids: list[int], learner_ids: list[int], in_lane: bool) -> None:
        """One step of these tasks and learners: reset, act, one physics call, learn."""
        with single_threaded() if in_lane else contextlib.nullcontext():  # the lanes already fill the cores
            for i in task_ids:
                observations[i] = tasks[i].reset()
            for j in learner_ids:
                i, part = owners[j], parts[j]
                actions[i][part] = learners[j].act(observations[i][part])
            stepped = step_together([tasks[i] for i in task_ids], [actions[i] for i in task_ids])
            for i, r in zip(task_ids, stepped, strict=True):
                rewards_of[i] = r
            for j in learner_ids:
                i, part = owners[j], parts[j]
                if episodic[i]:  # the next state and whether the episode ended there
                    done = cast(EpisodicTask, tasks[i])
                    learners[j].learn(rewards_of[i][part], done.next_observations[part], done.terminal[part])
                else:
                    learners[j].learn(rewards_of[i][part])

    start = time.perf_counter()
    step = 0
    interrupted = False
    with stop_between_steps() as stop, pool or contextlib.nullcontext():
        try:
            while step < n_steps:
                threaded = policy.threaded(step)
                began = time.perf_counter()
                if threaded:
                    others = [pool.submit(run_lane, lanes[k], members[k], True) for k in range(1, len(lanes))]
                    run_lane(lanes[0], members[0], True)
                    for other in others:
                        other.result()
                else:
                    run_lane(every_task, every_learner, False)
                policy.record(threaded, time.perf_counter() - began)
                rewards = rewards_of[0] if len(tasks) == 1 else np.concatenate(rewards_of)
                accumulated += rewards
                accumulated_sq += rewards * rewards
                step += 1
                if log is not None:
                    log.record(step, rewards)
                    for _, _, returns, _ in log.ended[seen:]:
                        recent.extend(returns.tolist())
                    seen = len(log.ended)
                if on_step is not None:
                    on_step(step, observations[0], actions[0], rewards)
                if step % block == 0:
                    index = step // block - 1
                    block_means[index] = accumulated / block
                    block_sq_means[index] = accumulated_sq / block
                    shown = _measures(block_means[index], one_step, recent, any(episodic))
                    accumulated[:] = 0.0
                    accumulated_sq[:] = 0.0
                    bar.update(step, shown)
                if step in snapshots_at:
                    for learner, taken in zip(learners, snapshots, strict=True):
                        taken[step] = snapshot(learner)
                if stop["requested"]:
                    interrupted = True
                    break
        except KeyboardInterrupt:  # raised by an on_step hook, or outside the main thread
            interrupted = True
    wall_time = time.perf_counter() - start
    bar.close(step, shown)
    done = step // block
    return Curves(block_means[:done], block_sq_means[:done], step, wall_time, interrupted, snapshots,
                  None if log is None else log.take())


def _measures(block_mean: np.ndarray | None, one_step: np.ndarray, recent: deque[float],
              any_episodic: bool) -> Measures:
    """What the progress bar shows: the last block's mean reward over the one-step tasks' trials (a
    single value when there are only those), the mean return of the ``recent`` finished episodes when
    there are episodic tasks, named; NaN where nothing is measured yet."""
    if not any_episodic:
        return float("nan") if block_mean is None else float(block_mean.mean())
    shown: dict[str, float] = {}
    if one_step.any():
        shown["mean reward"] = float("nan") if block_mean is None else float(block_mean[one_step].mean())
    name = f"mean return, last {len(recent)} episodes" if recent else "mean return"
    shown[name] = float(np.mean(recent)) if recent else float("nan")
    return shown


class _LanePolicy:
    """Whether a step runs its lanes in threads, by measurement.

    Every ``PERIOD`` steps, ``PROBE`` steps run in this thread alone, then ``PROBE`` in lanes; the
    rest of the period runs the way whose median step was shorter. Measured on 2 cores: Fig. 25's
    four 100-trial learners run about 1.15x faster in two lanes, while Fig. 24's groups of 20-trial
    learners, whose steps are mostly Python around the physics, run slower in lanes (the threads
    share the GIL, and each lane pays the longest flight's model steps).
    """

    PROBE = 16
    PERIOD = 1000

    def __init__(self, *, enabled: bool) -> None:
        self.enabled = enabled
        self.best = False
        self.probing = False
        self.times: dict[bool, list[float]] = {False: [], True: []}

    def threaded(self, step: int) -> bool:
        """Whether step ``step`` (0-based) runs in lanes."""
        if not self.enabled:
            return False
        phase = step % self.PERIOD
        self.probing = phase < 2 * self.PROBE
        if self.probing:
            return phase >= self.PROBE
        if self.times[False] and self.times[True]:  # the first step after a probe decides
            self.best = float(np.median(self.times[True])) < float(np.median(self.times[False]))
            self.times = {False: [], True: []}
        return self.best

    def record(self, threaded: bool, seconds: float) -> None:
        """The wall time of the step just asked about (kept while probing)."""
        if self.enabled and self.probing:
            self.times[threaded].append(seconds)


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
