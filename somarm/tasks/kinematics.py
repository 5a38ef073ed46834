"""Forward kinematics of a planar n-link arm (NumPy, vectorised over any leading shape).

Angles follow Smith (2002), Fig. 5: the first is measured from the x-axis, every later one
relative to the previous link, so link i points along the cumulative sum of angles 1..i.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

__all__ = ["BASE", "joint_positions", "forward"]

#: The arm's base in the unit square (Fig. 5).
BASE: tuple[float, float] = (0.5, 0.0)


def _checked(angles: object, lengths: object) -> tuple[np.ndarray, np.ndarray]:
    angles = np.asarray(angles, dtype=np.float64)
    lengths = np.asarray(lengths, dtype=np.float64)
    if lengths.ndim != 1 or lengths.size == 0:
        raise ValueError(f"lengths must be a non-empty 1-D array (one per link), got shape {lengths.shape}")
    if angles.ndim == 0 or angles.shape[-1] != lengths.size:
        raise ValueError(f"angles must have shape (..., {lengths.size}) (one per link), got {angles.shape}")
    return angles, lengths


def joint_positions(
    angles: np.ndarray, lengths: Sequence[float] | np.ndarray, base: Sequence[float] = BASE
) -> np.ndarray:
    """Positions of the base, every joint and the tip.

    Args:
      angles: joint angles in radians, shape ``(..., n_links)``; relative angles, the first
        from the x-axis.
      lengths: link lengths, shape ``(n_links,)``.
      base: (x, y) of the base.

    Returns:
      Array of shape ``(..., n_links + 1, 2)``: row 0 is the base, the last row the tip.

    Raises:
      ValueError: ``angles`` whose last axis does not match ``lengths``.
    """
    angles, lengths = _checked(angles, lengths)
    heading = np.cumsum(angles, axis=-1)
    steps = lengths[:, None] * np.stack([np.cos(heading), np.sin(heading)], axis=-1)
    points = np.empty((*angles.shape[:-1], lengths.size + 1, 2))
    points[..., 0, :] = base
    np.cumsum(steps, axis=-2, out=points[..., 1:, :])
    points[..., 1:, :] += np.asarray(base, dtype=np.float64)
    return points


def forward(
    angles: np.ndarray, lengths: Sequence[float] | np.ndarray, base: Sequence[float] = BASE
) -> np.ndarray:
    """Tip position of the arm, shape ``(..., 2)`` for angles of shape ``(..., n_links)``.

    See ``joint_positions`` for the arguments.
    """
    angles, lengths = _checked(angles, lengths)
    heading = np.cumsum(angles, axis=-1)
    tip = np.stack([np.cos(heading) @ lengths, np.sin(heading) @ lengths], axis=-1)
    return tip + np.asarray(base, dtype=np.float64)
