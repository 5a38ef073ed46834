"""The learning curves as training goes: each block's mean reward per trial, and the episodes that end."""

from __future__ import annotations

from collections import deque

import numpy as np

from somarm.protocols import BatchedTask
from somarm.run.episodes import EpisodeLog, Episodes
from somarm.run.progress import Measures

__all__ = ["BlockRecorder", "RECENT_EPISODES"]

#: The progress bar of an episodic task shows the mean return of this many last finished episodes
#: (as Stable-Baselines3's ``ep_rew_mean`` does), fewer until that many have ended.
RECENT_EPISODES = 100


class BlockRecorder:
    """Records every step's rewards of all trials side by side (the tasks' trials in task order).

    Each ``block`` steps make one point of the learning curves: the mean reward and mean squared
    reward of each trial over the block. The episodes of the multi-step tasks go to an ``EpisodeLog``
    (the one given, to go on with, or one made here), and the last ``RECENT_EPISODES`` returns feed
    the progress bar's ``measures``.

    Args:
      tasks: the tasks stepped together, in order.
      n_steps: the steps to be recorded at most. block: steps per point of the curves.
      episode_log: the log of the tasks' episodes to go on with (default: a new one, if any task is episodic).
    """

    def __init__(self, tasks: list[BatchedTask], *, n_steps: int, block: int,
                 episode_log: EpisodeLog | None = None) -> None:
        n_trials = sum(t.n_trials for t in tasks)
        self.block = block
        self.block_means = np.zeros((n_steps // block, n_trials))
        self.block_sq_means = np.zeros((n_steps // block, n_trials))
        self.accumulated = np.zeros(n_trials)
        self.accumulated_sq = np.zeros(n_trials)
        self.steps = 0
        episodic = [t.episodic for t in tasks]
        self.any_episodic = any(episodic)
        self.log = episode_log if episode_log is not None else (EpisodeLog(tasks) if self.any_episodic else None)
        # The bar shows each scale of reward apart: one-step tasks' mean reward, episodic tasks' mean return.
        self.one_step = np.concatenate([np.full(t.n_trials, not e) for t, e in zip(tasks, episodic, strict=True)])
        self.recent: deque[float] = deque(maxlen=RECENT_EPISODES)
        self.seen = 0 if self.log is None else len(self.log.ended)  # episodes the log held before this recording
        self.measures: Measures = self._measures(None)

    def record(self, rewards: np.ndarray) -> bool:
        """Add one step's rewards ``(n_trials,)``; whether that step completed a block."""
        self.accumulated += rewards
        self.accumulated_sq += rewards * rewards
        self.steps += 1
        if self.log is not None:
            self.log.record(self.steps, rewards)
            for _, _, returns, _ in self.log.ended[self.seen:]:
                self.recent.extend(returns.tolist())
            self.seen = len(self.log.ended)
        if self.steps % self.block:
            return False
        index = self.steps // self.block - 1
        self.block_means[index] = self.accumulated / self.block
        self.block_sq_means[index] = self.accumulated_sq / self.block
        self.measures = self._measures(self.block_means[index])
        self.accumulated[:] = 0.0
        self.accumulated_sq[:] = 0.0
        return True

    def curves(self) -> tuple[np.ndarray, np.ndarray, Episodes | None]:
        """The complete blocks' means and squared means ``(n_blocks, n_trials)``, and the episodes
        that ended while recording (None when no task is episodic)."""
        done = self.steps // self.block
        return (self.block_means[:done], self.block_sq_means[:done],
                None if self.log is None else self.log.take())

    def _measures(self, block_mean: np.ndarray | None) -> Measures:
        """What the progress bar shows: the last block's mean reward over the one-step tasks' trials (a
        single value when there are only those), the mean return of the recent finished episodes when
        there are episodic tasks, named; NaN where nothing is measured yet."""
        if not self.any_episodic:
            return float("nan") if block_mean is None else float(block_mean.mean())
        shown: dict[str, float] = {}
        if self.one_step.any():
            shown["mean reward"] = float("nan") if block_mean is None else float(block_mean[self.one_step].mean())
        name = f"mean return, last {len(self.recent)} episodes" if self.recent else "mean return"
        shown[name] = float(np.mean(self.recent)) if self.recent else float("nan")
        return shown
