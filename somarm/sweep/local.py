"""The local engine: chunks in this process, or in a few worker processes when asked.

In one process the chunks run one after another, each in lockstep (one physics call per step for
all its points). With ``workers > 1`` the chunks (different tasks or seeds, or a group cut for
memory) spread over that many processes.
"""

from __future__ import annotations

import concurrent.futures
import multiprocessing
import os
import signal
from collections.abc import Callable

from somarm.sweep.work import Chunk, failed_row, run_chunk

__all__ = ["run_local"]

RowSink = Callable[[dict], None]


def _work(chunk: dict, progress: bool) -> tuple[list[dict], bool]:
    return run_chunk(Chunk.from_dict(chunk), progress=progress)


def run_local(chunks: list[Chunk], save: RowSink, *, workers: int = 1, progress: bool = True) -> bool:
    """Run every chunk; each row goes to ``save`` as soon as its chunk is done.

    Args:
      chunks: the work (``plan_chunks``).
      save: called with each finished or failed row.
      workers: processes to use (1: this process).
      progress: progress bars on stderr.

    Returns:
      True when Ctrl-C or SIGTERM stopped the sweep (the rows saved so far are complete).
    """
    if workers <= 1 or len(chunks) <= 1:
        try:
            for chunk in chunks:
                rows, interrupted = run_chunk(chunk, progress=progress)
                for row in rows:
                    save(row)
                if interrupted:
                    return True
        except KeyboardInterrupt:
            return True
        return False
    # spawn, not fork: the parent may hold MuJoCo and numba threads that a fork would not carry.
    context = multiprocessing.get_context("spawn")
    pool = concurrent.futures.ProcessPoolExecutor(max_workers=workers, mp_context=context)
    futures = {pool.submit(_work, chunk.to_dict(), False): chunk for chunk in chunks}
    interrupted = False
    try:
        for future in concurrent.futures.as_completed(futures):
            try:
                rows, stopped = future.result()
            except Exception as exc:  # a worker process died: its points failed
                rows, stopped = [failed_row(i, s, c, exc) for i, s, c in futures[future].items], False
            for row in rows:
                save(row)
            interrupted |= stopped
    except KeyboardInterrupt:
        interrupted = True
        for future in futures:
            future.cancel()
        # A terminal's Ctrl-C reaches the workers too; a SIGTERM to this process alone does not.
        for pid in list(getattr(pool, "_processes", {}) or {}):
            try:
                os.kill(pid, signal.SIGINT)
            except ProcessLookupError:
                pass
        for future in futures:
            if not future.cancelled():
                try:
                    for row in future.result()[0]:
                        save(row)
                except (Exception, KeyboardInterrupt):  # a worker stopped mid-point
                    pass
    finally:
        pool.shutdown(wait=True, cancel_futures=True)
    return interrupted
