"""The worker threads the MuJoCo batches share (arms and projectiles): one pool per size, made once.

MuJoCo releases the GIL while it steps, so a large batch split over threads runs in parallel.
"""

from __future__ import annotations

import threading
from concurrent.futures import ThreadPoolExecutor

__all__ = ["shared_pool"]

_pools: dict[int, ThreadPoolExecutor] = {}
_lock = threading.Lock()


def shared_pool(workers: int) -> ThreadPoolExecutor:
    """The process's pool of ``workers`` threads, created on first use and kept for the next batch."""
    with _lock:
        if workers not in _pools:
            _pools[workers] = ThreadPoolExecutor(max_workers=workers, thread_name_prefix=f"somarm-{workers}")
        return _pools[workers]
