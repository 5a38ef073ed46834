"""The worker threads the MuJoCo batches share (arms and projectiles): one pool per size, made once.

MuJoCo releases the GIL while it steps, so a large batch split over threads runs in parallel.
A process that is itself one of several working side by side (the shares of a long lockstep group,
``somarm.run.split``) keeps its batches to itself: ``single_threaded`` holds ``threads_here`` at 1.
"""

from __future__ import annotations

import contextlib
import threading
from collections.abc import Iterator
from concurrent.futures import ThreadPoolExecutor

__all__ = ["shared_pool", "threads_here", "single_threaded"]

_limit = threading.local()


def threads_here(default: int) -> int:
    """Threads a batch started in this thread may use: ``default``, or 1 under ``single_threaded``."""
    return 1 if getattr(_limit, "single", False) else default


@contextlib.contextmanager
def single_threaded() -> Iterator[None]:
    """Within the block, batches started by this thread run in it alone (no pool threads)."""
    before = getattr(_limit, "single", False)
    _limit.single = True
    try:
        yield
    finally:
        _limit.single = before

_pools: dict[int, ThreadPoolExecutor] = {}
_lock = threading.Lock()


def shared_pool(workers: int) -> ThreadPoolExecutor:
    """The process's pool of ``workers`` threads, created on first use and kept for the next batch."""
    with _lock:
        if workers not in _pools:
            _pools[workers] = ThreadPoolExecutor(max_workers=workers, thread_name_prefix=f"somarm-{workers}")
        return _pools[workers]
