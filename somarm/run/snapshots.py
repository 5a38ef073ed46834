"""Copies of what the learners have learned, taken after the steps asked for (figures mid-run)."""

from __future__ import annotations

import numpy as np

from somarm.protocols import Learner

__all__ = ["snapshot", "Snapshots"]


def snapshot(learner: Learner) -> dict[str, np.ndarray]:
    """Copies of the arrays that show what a learner has learned (its ``learned_arrays``), for figures mid-run."""
    return {name: np.array(getattr(learner, name)) for name in learner.learned_arrays}


class Snapshots:
    """Each learner's ``snapshot`` after every step in ``at``: ``taken[j][step]`` for learner j."""

    def __init__(self, learners: list[Learner], at: tuple[int, ...]) -> None:
        self.learners = learners
        self.at = frozenset(at)
        self.taken: list[dict[int, dict[str, np.ndarray]]] = [{} for _ in learners]

    def after(self, step: int) -> None:
        """Take the snapshots of step ``step`` (1-based) if it is one asked for."""
        if step in self.at:
            for learner, taken in zip(self.learners, self.taken, strict=True):
                taken[step] = snapshot(learner)
