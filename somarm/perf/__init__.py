"""Speed and memory figures: scripts that print them (never timed tests). Run with ``somarm bench NAME``."""

from __future__ import annotations

import time

__all__ = ["best_seconds"]


def best_seconds(fn, repeats: int) -> float:
    """Best wall-clock seconds of ``repeats`` calls of ``fn``, after one untimed call (MuJoCo's
    batch models, numba's and dm_control's first calls are made there)."""
    fn()
    best = float("inf")
    for _ in range(repeats):
        start = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - start)
    return best
