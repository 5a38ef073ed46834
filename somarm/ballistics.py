"""Closed-form flight of the projectile (Smith 2002, Eqs. 5 to 8), with mass and wind in general.

Vertically only gravity acts, so the height is ``u_y t - G t^2 / 2`` and the projectile is back
at height 0 at ``T = 2 u_y / G`` (Eq. 5). Horizontally ``M dv/dt = -Fr (v + W)``: the quantity
``v + W`` decays at the rate ``k = Fr / M`` (the paper's Eq. 6 is the case M = 1), so

    s_x(T) = (u_x + W) (1 - exp(-k T)) / k - W T                       (Eq. 7 with k = Fr / M)
    u_x    = k (X + W T) / (1 - exp(-k T)) - W                          (Eq. 8, solved for u_x)

As Fr -> 0, ``(1 - exp(-k T)) / k -> T`` and the flight is drag-free; ``_decay_length`` below
evaluates that factor without dividing by zero. Every function broadcasts over NumPy arrays.
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "flight_time",
    "landing_x",
    "landing_gradient",
    "landing_range",
    "solution_ux",
]


def flight_time(uy: np.ndarray | float, G: float = 0.05) -> np.ndarray:
    """Time at which the projectile is back at height 0: ``2 u_y / G`` (from Eq. 5)."""
    return 2.0 * np.asarray(uy, dtype=np.float64) / G


def _decay_length(k: np.ndarray, T: np.ndarray) -> np.ndarray:
    """``(1 - exp(-k T)) / k``, equal to ``T`` in the limit k -> 0 (no drag)."""
    kT = np.asarray(k * T, dtype=np.float64)
    ratio = np.ones_like(kT)
    nonzero = kT != 0
    # -expm1(-z) / z is accurate for tiny z, where 1 - exp(-z) would lose every digit.
    np.divide(-np.expm1(-kT), kT, out=ratio, where=nonzero)
    return T * ratio


def landing_x(
    ux: np.ndarray | float, uy: np.ndarray | float, *, G: float = 0.05, Fr: np.ndarray | float = 0.1,
    W: np.ndarray | float = 0.0, M: np.ndarray | float = 1.0,
) -> np.ndarray:
    """Horizontal landing position (Eq. 7 with mass M); all arguments broadcast.

    Args:
      ux, uy: launch velocity components.
      G: gravity (> 0). Fr: drag coefficient (>= 0). W: wind against the thrower. M: mass (> 0).

    Returns:
      Landing x, the broadcast shape of the arguments.
    """
    k = np.asarray(Fr, dtype=np.float64) / M
    T = flight_time(uy, G)
    return (np.asarray(ux, dtype=np.float64) + W) * _decay_length(k, T) - W * T


def landing_gradient(
    ux: np.ndarray | float, uy: np.ndarray | float, *, G: float = 0.05, Fr: np.ndarray | float = 0.1,
    W: np.ndarray | float = 0.0, M: np.ndarray | float = 1.0,
) -> tuple[np.ndarray, np.ndarray]:
    """Partial derivatives of ``landing_x`` with respect to ``ux`` and ``uy`` (exact).

    ``d/dux = (1 - exp(-kT)) / k`` and ``d/duy = (2 / G) ((ux + W) exp(-kT) - W)``.

    Returns:
      ``(d_ux, d_uy)``, each of the broadcast shape.
    """
    k = np.asarray(Fr, dtype=np.float64) / M
    T = flight_time(uy, G)
    d_ux = _decay_length(k, T)
    d_uy = (2.0 / G) * ((np.asarray(ux, dtype=np.float64) + W) * np.exp(-k * T) - W)
    return d_ux, d_uy


def _extreme_over_uy(ux: float, *, G, Fr, W, M, largest: bool) -> np.ndarray:
    """Largest (or smallest) landing over uy in [0, 1] for a fixed ux, per parameter set."""
    k = np.asarray(Fr, dtype=np.float64) / M
    W = np.asarray(W, dtype=np.float64)
    ends = [landing_x(ux, 0.0, G=G, Fr=Fr, W=W, M=M), landing_x(ux, 1.0, G=G, Fr=Fr, W=W, M=M)]
    # d s_x / dT = (ux + W) exp(-kT) - W vanishes once at most: exp(-kT*) = W / (ux + W).
    with np.errstate(divide="ignore", invalid="ignore"):
        T_star = -np.log(W / (ux + W)) / k
    uy_star = T_star * G / 2.0
    inside = np.isfinite(uy_star) & (uy_star > 0.0) & (uy_star < 1.0)
    middle = landing_x(ux, np.where(inside, uy_star, 0.0), G=G, Fr=Fr, W=W, M=M)
    stack = np.stack(np.broadcast_arrays(*ends, np.where(inside, middle, ends[0])))
    return stack.max(axis=0) if largest else stack.min(axis=0)


def landing_range(
    *, G: float = 0.05, Fr: np.ndarray | float = 0.1, W: np.ndarray | float = 0.0,
    M: np.ndarray | float = 1.0,
) -> tuple[np.ndarray, np.ndarray]:
    """Smallest and largest landing x over the velocity square [0, 1]^2, per parameter set.

    The landing grows with ux (its ux-derivative is >= 0), so the largest is on ux = 1 and the
    smallest on ux = 0; along uy there is at most one interior extremum, found in closed form.

    Returns:
      ``(lowest, highest)``, each of the broadcast shape of the parameters.
    """
    params = {"G": G, "Fr": Fr, "W": W, "M": M}
    return _extreme_over_uy(0.0, largest=False, **params), _extreme_over_uy(1.0, largest=True, **params)


def solution_ux(
    uy: np.ndarray | float, *, X: np.ndarray | float = 4.0, G: float = 0.05, Fr: np.ndarray | float = 0.1,
    W: np.ndarray | float = 0.0, M: np.ndarray | float = 1.0,
) -> np.ndarray:
    """The ux that lands on the target X for each uy (Eq. 8, the curve of Fig. 18).

    Returns:
      ux of the broadcast shape; NaN where no ux in [0, 1] reaches X with that uy
      (including uy = 0, unless X = 0).
    """
    k = np.asarray(Fr, dtype=np.float64) / M
    T = flight_time(uy, G)
    length = _decay_length(k, T)
    with np.errstate(divide="ignore", invalid="ignore"):
        ux = (X + W * T) / length - W
    at_origin = (T == 0) & (np.asarray(X) == 0)
    ux = np.where(at_origin, 0.0, ux)
    return np.where(np.isfinite(ux) & (ux >= 0.0) & (ux <= 1.0), ux, np.nan)
