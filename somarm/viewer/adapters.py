"""Where the tasks keep goals, targets and flights, read in one place for the viewer."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

__all__ = ["goal_adapter", "throw_adapters"]


def goal_adapter(task_name: str, task=None) -> Callable[[np.ndarray], np.ndarray] | None:
    """Observation ``(obs_dim,)`` -> goal (x, y) for the arm tasks; None means "the first two values"."""
    return None


def throw_adapters(task_name: str, task=None):
    """``(trajectory(ux, uy) -> (n_points, 2), target_of(observation) -> x)`` for a throwing task."""
    raise NotImplementedError
