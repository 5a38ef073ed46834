"""Measures behind the report's verdicts: failed trials, topology, curve distances, spacing, speed of learning.

Pure NumPy on plain arrays, so every verdict in REPORT.md can be recomputed and tested alone.
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "FAILED_FACTOR",
    "EDGE_WIDTH",
    "failed_trials",
    "edge_share",
    "chebyshev_distances",
    "topographic_error",
    "nearest_is_neighbour",
    "greedy_jumps",
    "distance_to_polyline",
    "spacing_cv",
    "centred_mean",
    "steps_to_level",
    "spearman",
]

#: A trial has failed when its error is above this multiple of the median error over the run's trials
#: (docs/results.md, "How results are measured", says so for every report).
FAILED_FACTOR = 2.0


def failed_trials(errors: np.ndarray, factor: float = FAILED_FACTOR) -> np.ndarray:
    """Which trials failed: an error above ``factor`` times the median error over the trials.

    The one definition every report and doc counts failed trials by. Relative to the median, so it
    reads the same on every task and measure (a distance, a miss, a training error), as the paper's
    Fig. 8 does ("failed to achieve close to mean performance"); the median, not the mean, so the
    failed trials do not raise their own threshold.

    Args:
      errors: ``(n_trials,)`` one error per trial (lower is better, >= 0).
      factor: the multiple of the median above which a trial has failed (> 1).

    Returns:
      ``(n_trials,)`` bools, True for a failed trial.

    Raises:
      ValueError: no trial, a non-finite error, or ``factor`` not above 1.
    """
    errors = np.asarray(errors, dtype=float)
    if errors.ndim != 1 or errors.size == 0 or not np.isfinite(errors).all():
        raise ValueError(f"errors must be a non-empty 1-D array of finite numbers, got shape {errors.shape}")
    if not factor > 1.0:
        raise ValueError(f"factor must be above 1, got {factor!r}")
    return errors > factor * float(np.median(errors))


#: An action unit sits at the box's edge when one of its angles is within this of a bound (rad).
EDGE_WIDTH = 0.06


def edge_share(action_weights: np.ndarray, low: np.ndarray, high: np.ndarray | None = None,
               width: float = EDGE_WIDTH) -> np.ndarray:
    """The share of each trial's action units piled at the edge of the action box.

    A unit counts when one of its dimensions lies within ``width`` of that dimension's lower bound
    (for the arms: an angle within 0.06 rad of -pi), or of its upper bound when ``high`` is given.

    Args:
      action_weights: ``(n_trials, n_units, action_dim)``.
      low: ``(action_dim,)`` the lower bounds; high: the upper bounds, or None for the lower edge only.
      width: how near a bound counts as at it.

    Returns:
      ``(n_trials,)`` shares in [0, 1].
    """
    weights = np.asarray(action_weights, dtype=float)
    near = weights - np.asarray(low, dtype=float) < width
    if high is not None:
        near |= np.asarray(high, dtype=float) - weights < width
    return near.any(axis=-1).mean(axis=-1)


def chebyshev_distances(grid: np.ndarray) -> np.ndarray:
    """Chebyshev distances between units on a map grid: ``(n_units, 2) -> (n_units, n_units)``.

    Two units are neighbours when this distance is 1 (the 8-neighbourhood on a 2-D grid).
    """
    grid = np.asarray(grid, dtype=float)
    return np.abs(grid[:, None, :] - grid[None, :, :]).max(axis=-1)


def topographic_error(weights: np.ndarray, grid: np.ndarray, samples: np.ndarray) -> float:
    """Fraction of samples whose best and second-best units are not grid neighbours.

    Args:
      weights: ``(n_units, dim)`` map weights. grid: ``(n_units, 2)``. samples: ``(n, dim)``.
    """
    d = ((samples[:, None, :] - weights[None, :, :]) ** 2).sum(axis=-1)
    order = np.argsort(d, axis=1)[:, :2]
    return float((chebyshev_distances(grid)[order[:, 0], order[:, 1]] > 1).mean())


def nearest_is_neighbour(weights: np.ndarray, grid: np.ndarray) -> float:
    """Fraction of units whose nearest other unit in weight space is a grid neighbour."""
    d = ((weights[:, None, :] - weights[None, :, :]) ** 2).sum(axis=-1)
    np.fill_diagonal(d, np.inf)
    nearest = d.argmin(axis=1)
    return float((chebyshev_distances(grid)[np.arange(len(weights)), nearest] <= 1).mean())


def greedy_jumps(greedy: np.ndarray, input_grid: np.ndarray, action_grid: np.ndarray) -> np.ndarray:
    """Grid distance between the greedy action units of every pair of neighbouring input units.

    Args:
      greedy: ``(n_input_units,)`` greedy action unit of each input unit.

    Returns:
      ``(n_pairs,)`` action-grid distances (0 or 1 where the Q-table keeps topology).
    """
    neighbours = np.argwhere(np.triu(chebyshev_distances(input_grid) == 1))
    action_d = chebyshev_distances(action_grid)
    return action_d[greedy[neighbours[:, 0]], greedy[neighbours[:, 1]]]


def distance_to_polyline(points: np.ndarray, polyline: np.ndarray) -> np.ndarray:
    """Euclidean distance of each point to a polyline: ``(n, 2), (m, 2) -> (n,)``.

    NaN rows of the polyline split it into separate pieces (no segment spans a NaN).
    """
    a, b = polyline[:-1], polyline[1:]
    keep = np.isfinite(a).all(axis=1) & np.isfinite(b).all(axis=1)
    a, b = a[keep], b[keep]
    ab = b - a
    length2 = np.maximum((ab**2).sum(axis=1), 1e-300)
    s = np.clip(((points[:, None, :] - a[None]) * ab[None]).sum(axis=-1) / length2, 0.0, 1.0)
    closest = a[None] + s[..., None] * ab[None]
    return np.sqrt(((points[:, None, :] - closest) ** 2).sum(axis=-1)).min(axis=1)


def spacing_cv(values: np.ndarray) -> float:
    """Coefficient of variation (sd / mean) of the gaps between sorted values."""
    gaps = np.diff(np.sort(np.asarray(values, dtype=float).ravel()))
    return float(gaps.std() / gaps.mean()) if gaps.size and gaps.mean() > 0 else float("nan")


def centred_mean(values: np.ndarray, half_width: int) -> np.ndarray:
    """Mean over the ``2 half_width + 1`` rows centred on each row (fewer at the ends), same shape.

    Unlike a trailing mean it does not lag, so the step at which a curve crosses a level is not
    pushed later by half a window (which would bias a ratio of two such steps towards 1).
    """
    values = np.asarray(values, dtype=float)
    cumulative = np.concatenate([np.zeros((1, *values.shape[1:])), np.cumsum(values, axis=0)])
    index = np.arange(len(values))
    lo = np.maximum(0, index - half_width)
    hi = np.minimum(len(values), index + half_width + 1)
    counts = (hi - lo).reshape(-1, *([1] * (values.ndim - 1)))
    return (cumulative[hi] - cumulative[lo]) / counts


def steps_to_level(steps: np.ndarray, error: np.ndarray, level: float) -> float:
    """First step at which an error curve is at or below ``level`` (NaN if it never is)."""
    hits = np.flatnonzero(np.asarray(error) <= level)
    return float(steps[hits[0]]) if hits.size else float("nan")


def spearman(x: np.ndarray, y: np.ndarray) -> float:
    """Spearman rank correlation of two 1-D samples (ties ranked by order, fine for continuous data)."""
    rx = np.argsort(np.argsort(x)).astype(float)
    ry = np.argsort(np.argsort(y)).astype(float)
    return float(np.corrcoef(rx, ry)[0, 1])
