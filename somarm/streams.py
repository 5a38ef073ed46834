"""Per-trial random streams: trial i draws the same numbers alone or inside a batch.

Every random number in somarm comes from an ``np.random.Generator`` seeded from the run's
seed, the purpose of the draws (learner, task, evaluation) and the trial's index. Drawing
from 100 generators one number at a time would cost more than the learner itself, so each
stream draws a block of rows at once and hands them out row by row; the rows a trial sees
do not depend on the block size or on which other trials share the batch.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

__all__ = ["PURPOSES", "trial_ids_for", "trial_generators", "UniformStreams"]

#: Each kind of draw gets its own family of streams, so that adding draws to one
#: (say, the task) never shifts the numbers of another (the learner).
PURPOSES: dict[str, int] = {"learner": 1, "task": 2, "evaluation": 3, "viewer": 4, "scaling": 5}


def trial_ids_for(n_trials: int, trial_ids: Sequence[int] | None = None) -> np.ndarray:
    """The trial indices of a batch: ``range(n_trials)`` unless given explicitly.

    Args:
      n_trials: number of trials in the batch (>= 1).
      trial_ids: optional explicit indices, e.g. ``[7]`` to replay trial 7 alone.

    Returns:
      Integer array of shape ``(n_trials,)``.

    Raises:
      ValueError: ``n_trials < 1``, or ``trial_ids`` of the wrong length or negative.
    """
    if isinstance(n_trials, bool) or not isinstance(n_trials, (int, np.integer)) or n_trials < 1:
        raise ValueError(f"n_trials must be a whole number >= 1, got {n_trials!r}")
    if trial_ids is None:
        return np.arange(n_trials)
    ids = np.asarray(trial_ids)
    if ids.shape != (n_trials,) or not np.issubdtype(ids.dtype, np.integer) or (ids < 0).any():
        raise ValueError(
            f"trial_ids must be {n_trials} whole numbers >= 0 (one per trial), got {ids.tolist()!r}"
        )

    return ids.astype(np.int64)


def trial_generators(seed: int, trial_ids: np.ndarray, purpose: str, *, start: int = 0) -> list[np.random.Generator]:
    """One independent generator per trial, derived from (seed, purpose, trial index), and from
    ``start`` where it is not 0: a run that goes on from step ``start`` of a saved learner draws from
    streams of its own instead of replaying those it began with.

    Args:
      seed: the run's seed (a whole number >= 0).
      trial_ids: trial indices, shape ``(n_trials,)``.
      purpose: one of ``PURPOSES``.

    Returns:
      A list of ``n_trials`` PCG64 generators.
    """
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise ValueError(f"seed must be a whole number >= 0, got {seed!r}")
    if purpose not in PURPOSES:
        raise ValueError(f"unknown purpose {purpose!r}; allowed: {', '.join(PURPOSES)}")
    return [
        np.random.Generator(
            np.random.PCG64(np.random.SeedSequence(
                int(seed), spawn_key=(PURPOSES[purpose], int(i)) + ((int(start),) if start else ())))
        )
        for i in trial_ids
    ]


class UniformStreams:
    """Rows of uniform [0, 1) numbers, one independent stream per trial, drawn in blocks.

    ``next()`` returns an array of shape ``(n_trials, width)``: row t of every trial's
    stream. Trial i's rows depend only on (seed, purpose, trial_ids[i], width).

    Args:
      seed: the run's seed.
      trial_ids: trial indices, shape ``(n_trials,)`` (see ``trial_ids_for``).
      purpose: one of ``PURPOSES``.
      width: numbers per row (>= 1).
      block: rows drawn at a time; a speed knob only, it never changes the numbers.
      start: a step to go on from (``trial_generators``); 0, the default, for a run from its start.
    """

    def __init__(self, seed: int, trial_ids: np.ndarray, purpose: str, width: int, *, block: int = 512,
                 start: int = 0):
        if width < 1 or block < 1:
            raise ValueError(f"width and block must be >= 1, got width={width}, block={block}")
        self.width = int(width)
        self.block = int(block)
        self._generators = trial_generators(seed, np.asarray(trial_ids), purpose, start=start)
        self._buffer = np.empty((len(self._generators), self.block, self.width))
        self._pos = self.block  # empty: the first next() refills

    @property
    def n_trials(self) -> int:
        return len(self._generators)

    def _refill(self) -> None:
        for i, generator in enumerate(self._generators):
            # Draw row by row in C order: the same numbers whatever the block size.
            self._buffer[i] = generator.random((self.block, self.width))
        self._pos = 0

    def next(self) -> np.ndarray:
        """The next row of every trial's stream, shape ``(n_trials, width)`` (a view)."""
        if self._pos == self.block:
            self._refill()
        row = self._buffer[:, self._pos]
        self._pos += 1
        return row

    # -- save / restore -------------------------------------------------------------------
    def get_state(self) -> dict[str, Any]:
        """Everything needed to continue the streams exactly: JSON-able plus one array."""
        return {
            "width": self.width,
            "block": self.block,
            "pos": self._pos,
            "bit_generators": [g.bit_generator.state for g in self._generators],
            "buffer": self._buffer.copy(),
        }

    def set_state(self, state: dict[str, Any]) -> None:
        """Restore a state from ``get_state`` (same number of trials)."""
        if len(state["bit_generators"]) != self.n_trials:
            raise ValueError(
                f"stream state holds {len(state['bit_generators'])} trials, expected {self.n_trials}"
            )
        self.width, self.block, self._pos = int(state["width"]), int(state["block"]), int(state["pos"])
        for generator, bit_state in zip(self._generators, state["bit_generators"], strict=True):
            generator.bit_generator.state = bit_state
        self._buffer = np.array(state["buffer"], dtype=float).reshape(self.n_trials, self.block, self.width)
