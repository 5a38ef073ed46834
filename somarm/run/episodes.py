"""The training episodes of the multi-step tasks: collected as they end (``EpisodeLog``), kept as ``Episodes``."""

from __future__ import annotations

from dataclasses import dataclass
from typing import cast

import numpy as np

from somarm.protocols import BatchedTask, EpisodicTask

__all__ = ["Episodes", "EpisodeLog"]


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
