"""Argument checks that fail with one clear line naming the argument and what is allowed."""

from __future__ import annotations

import math

import numpy as np

__all__ = [
    "check_int",
    "check_number",
    "check_array",
    "check_bounds",
]


def check_int(name: str, value: object, *, minimum: int = 1) -> int:
    """``value`` as an int >= ``minimum``; ValueError naming ``name`` otherwise."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < minimum:
        raise ValueError(f"{name} must be a whole number >= {minimum}, got {value!r}")
    return int(value)


def check_number(
    name: str, value: object, *, minimum: float | None = None, maximum: float | None = None,
    strict_minimum: bool = False,
) -> float:
    """``value`` as a finite float inside the given range; ValueError naming ``name``."""
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise ValueError(f"{name} must be a number, got {value!r}")
    value = float(value)
    if not math.isfinite(value):
        raise ValueError(f"{name} must be finite, got {value!r}")
    if minimum is not None and (value <= minimum if strict_minimum else value < minimum):
        sign = ">" if strict_minimum else ">="
        raise ValueError(f"{name} must be {sign} {minimum}, got {value!r}")
    if maximum is not None and value > maximum:
        raise ValueError(f"{name} must be <= {maximum}, got {value!r}")
    return value


def check_array(name: str, value: object, shape: tuple[int | None, ...]) -> np.ndarray:
    """``value`` as a finite float64 array of ``shape`` (None matches any length).

    Raises:
      ValueError: wrong shape (both shapes are named), or NaN/inf entries.
    """
    try:
        array = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be an array of numbers, got {type(value).__name__}") from None
    if array.ndim != len(shape) or any(
        want is not None and got != want for got, want in zip(array.shape, shape, strict=True)
    ):
        expected = "(" + ", ".join("any" if s is None else str(s) for s in shape) + ")"
        raise ValueError(f"{name} must have shape {expected}, got {array.shape}")
    if not np.isfinite(array).all():
        raise ValueError(f"{name} must be finite, got NaN or inf")
    return array


def check_bounds(name: str, low: object, high: object) -> tuple[np.ndarray, np.ndarray]:
    """Validate a box: 1-D finite ``low`` < ``high`` elementwise, same length."""
    low_arr = check_array(f"{name} low", np.atleast_1d(low), (None,))
    high_arr = check_array(f"{name} high", np.atleast_1d(high), low_arr.shape)
    if low_arr.size == 0:
        raise ValueError(f"{name} bounds must have at least one dimension")
    if not (low_arr < high_arr).all():
        raise ValueError(f"{name} bounds need low < high in every dimension, got {low_arr} and {high_arr}")
    return low_arr, high_arr
