"""The self-organising map, batched over independent trials: grid, winner, neighbourhood, update.

Weights have shape ``(n_trials, n_units, dim)``; a single map is ``n_trials == 1``.

Grid distance: units of a ``(rows, cols)`` map sit at integer coordinates ``(r, c)`` and the
distance d between two units is the Euclidean distance between their coordinates, the usual
Kohonen choice. It makes the linear neighbourhood ``max(0, 1 - d/(N+1))`` a disc rather than
a square (Chebyshev) or a diamond (Manhattan), so a 2-D map is pulled the same amount in
every grid direction and no diagonal is favoured; for a 1-D map all three agree. The Table 2
and 7 widths (10 x f and 7 x f on a 10 x 10 map) then shrink from "the whole map" to "the
winner alone" smoothly, with no corner reached earlier than the edge midpoints.

Ties: the winner is the lowest-index unit among equally near ones (``argmin``).
"""

from __future__ import annotations

import numpy as np

from somarm.validation import check_int

__all__ = [
    "map_shape",
    "grid_coordinates",
    "grid_distances",
    "distances_from",
    "grid_offsets",
    "neighbourhood",
    "squared_distances",
    "winners",
    "update",
]


def map_shape(name: str, shape: object) -> tuple[int, ...]:
    """Validate a map shape: ``(n,)`` or ``(rows, cols)`` of whole numbers >= 1.

    Raises:
      ValueError: naming ``name`` and what is allowed.
    """
    if isinstance(shape, (int, np.integer)) and not isinstance(shape, bool):
        shape = (shape,)
    if not isinstance(shape, (tuple, list)) or not 1 <= len(shape) <= 2:
        raise ValueError(f"{name} must be (n,) or (rows, cols), got {shape!r}")
    return tuple(check_int(f"{name} size", size, minimum=1) for size in shape)


def grid_coordinates(shape: tuple[int, ...]) -> np.ndarray:
    """Grid coordinates of the units of a map, row-major (unit ``r * cols + c`` sits at ``(r, c)``).

    Args:
      shape: ``(n,)`` (a line, coordinates ``(i, 0)``) or ``(rows, cols)``.

    Returns:
      Float array ``(n_units, 2)``.
    """
    rows, cols = (shape[0], 1) if len(shape) == 1 else shape
    r, c = np.meshgrid(np.arange(rows), np.arange(cols), indexing="ij")
    return np.stack([r.ravel(), c.ravel()], axis=1).astype(np.float64)


def grid_distances(coordinates: np.ndarray) -> np.ndarray:
    """Euclidean grid distance between every pair of units, ``(n_units, n_units)``."""
    return distances_from(coordinates, np.arange(coordinates.shape[0]))


def distances_from(coordinates: np.ndarray, centres) -> np.ndarray:
    """Euclidean grid distance from each centre unit to every unit, row ``centres`` of ``grid_distances``
    without the ``(n_units, n_units)`` matrix (800 MB for a 100 x 100 map).

    Args:
      coordinates: ``grid_coordinates`` of the map, ``(n_units, 2)``.
      centres: unit indices, any shape.

    Returns:
      ``centres.shape + (n_units,)``; the same numbers as the rows of ``grid_distances``.
    """
    delta = coordinates[np.asarray(centres)][..., None, :] - coordinates
    return np.sqrt((delta * delta).sum(axis=-1))


def grid_offsets(shape: tuple[int, ...]) -> np.ndarray:
    """Grid distance by offset: entry ``[dr, dc]`` is the distance between two units ``dr`` rows and
    ``dc`` columns apart, ``(rows, cols)`` (``(n, 1)`` for a line). The compiled kernels read
    distances from it (``somarm.learners._kernels.grid_distance``): a lookup as cheap as a row of
    ``grid_distances``, for one number per unit instead of one per pair."""
    rows, cols = (shape[0], 1) if len(shape) == 1 else shape
    dr, dc = np.meshgrid(np.arange(rows, dtype=np.float64), np.arange(cols, dtype=np.float64), indexing="ij")
    return np.sqrt(dr * dr + dc * dc)


def neighbourhood(distances: np.ndarray, width: float) -> np.ndarray:
    """The paper's linear neighbourhood ``psi = max(0, 1 - d / (N + 1))``.

    Args:
      distances: grid distances from the centre unit, any shape.
      width: the neighbourhood size N (>= 0); N = 0 leaves the centre unit alone at 1.

    Returns:
      Values in [0, 1], the shape of ``distances``.
    """
    return np.maximum(0.0, 1.0 - distances / (width + 1.0))


def squared_distances(weights: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Squared Euclidean distance of every unit to ``x``, summed dimension by dimension.

    The sum runs in dimension order (not NumPy's pairwise order) so that the compiled kernel
    and the line-by-line reference give bit-identical distances.

    Args:
      weights: ``(..., n_units, dim)``.
      x: ``(..., dim)``.

    Returns:
      ``(..., n_units)``.
    """
    total = np.zeros(np.broadcast_shapes(weights.shape[:-1], x.shape[:-1] + (1,)))
    for i in range(weights.shape[-1]):
        diff = x[..., None, i] - weights[..., i]
        total += diff * diff
    return total


def winners(weights: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Index of the nearest unit (squared Euclidean distance), lowest index on a tie.

    Args:
      weights: ``(n_trials, n_units, dim)``.
      x: ``(n_trials, dim)``, or ``(n_trials, n_obs, dim)`` for several inputs per trial.

    Returns:
      ``(n_trials,)`` or ``(n_trials, n_obs)`` integer array.
    """
    if x.ndim == 3:
        return np.argmin(squared_distances(weights[:, None], x), axis=-1)
    return np.argmin(squared_distances(weights, x), axis=-1)


def update(
    weights: np.ndarray, x: np.ndarray, centres: np.ndarray, rate: float, width: float,
    coordinates: np.ndarray, *, mask: np.ndarray | None = None,
) -> None:
    """The SOM update, in place: ``w_m += rate * psi(centre, m, width) * (x - w_m)`` for every unit m.

    Args:
      weights: ``(n_trials, n_units, dim)``, changed in place.
      x: targets ``(n_trials, dim)``.
      centres: the unit each trial's neighbourhood is centred on, ``(n_trials,)``.
      rate: learning rate (lambda).
      width: neighbourhood size N.
      coordinates: ``grid_coordinates`` of the map, ``(n_units, 2)``.
      mask: optional ``(n_trials,)`` bool; trials where it is False do not move.
    """
    rates = rate * neighbourhood(distances_from(coordinates, centres), width)  # (n_trials, n_units)
    if mask is not None:
        rates = np.where(mask[:, None], rates, 0.0)
    weights += rates[:, :, None] * (x[:, None, :] - weights)
