"""A lockstep group trained in several processes: its configs shared out, each share a group of its own.

The configs of a group are independent (each trial draws from its own seeds; the shared physics
call is only a saving), so a group can be cut into shares trained side by side: the first share
in this process, each other in a worker process started fresh (``spawn``). Processes, unlike threads,
do not share Python's GIL, so the shares train side by side on separate cores; a worker's start-up
is the price, so only a group long enough to repay it is worth cutting. Each result equals the
config's result in one group, and a run alone.

A worker starts with Ctrl-C ignored, so Ctrl-C reaches this process alone: its own share stops
between two steps, and it sends every worker SIGTERM, which stops the worker's share the same way;
every share comes back, marked interrupted.
"""

from __future__ import annotations

import multiprocessing
import os
import signal

from somarm.run import RunConfig, RunResult, share_lanes, train_group
from somarm.run.workers import outcome, start
from somarm.tasks.pool import single_threaded

__all__ = ["train_split"]


def _worker(connection, configs: list[RunConfig], snapshots_at: tuple[int, ...]) -> None:
    """Train one share (physics in this process's one thread) and send ``workers.outcome``'s answer."""
    from somarm import tasks

    tasks.set_threads(1)
    try:
        connection.send(outcome(lambda: train_group(configs, progress=False, snapshots_at=snapshots_at)))
    except BrokenPipeError:  # the parent died (its death stopped this share): nobody to answer
        pass
    finally:
        connection.close()


def train_split(configs: list[RunConfig], *, processes: int, progress: bool = True, label: str | None = None,
                snapshots_at: tuple[int, ...] = ()) -> list[RunResult]:
    """``train_group`` with the configs shared out between ``processes`` processes (``share_lanes``).

    Returns:
      One ``RunResult`` per config, in order; all marked interrupted when a stop came.

    Raises:
      ValueError: a bad setting (a worker's one-line error).
      RuntimeError: a worker crashed (its traceback in the message) or died without an answer.
    """
    lane_of = share_lanes([c.n_trials for c in configs], processes)
    shares = [[j for j in range(len(configs)) if lane_of[j] == k] for k in range(max(lane_of) + 1)]
    if len(shares) == 1:
        return train_group(configs, progress=progress, label=label, snapshots_at=snapshots_at)
    context = multiprocessing.get_context("spawn")
    workers = []
    for share in shares[1:]:
        workers.append(start(context, _worker, ([configs[j] for j in share], snapshots_at), name="somarm-share",
                             duplex=False, daemon=True))
    results: list[RunResult | None] = [None] * len(configs)
    stopped = False
    try:
        with single_threaded():  # the shares already fill the cores
            own = train_group([configs[j] for j in shares[0]], progress=progress, label=label,
                              snapshots_at=snapshots_at)
    except BaseException:
        _terminate(workers)
        raise
    for j, result in zip(shares[0], own, strict=True):
        results[j] = result
    if any(r.interrupted for r in own):
        stopped = True
        _terminate(workers)
    for share, (connection, process) in zip(shares[1:], workers, strict=True):
        while True:
            try:
                kind, payload = connection.recv()
                break
            except KeyboardInterrupt:  # a stop while waiting: the workers stop too, and answer
                stopped = True
                _terminate(workers)
            except EOFError:
                if stopped:  # ended by the stop before its training began: nothing to keep
                    _terminate(workers)
                    raise KeyboardInterrupt from None
                kind, payload = "crash", f"its process ended without an answer (exit code {process.exitcode})"
                break
        process.join()
        connection.close()
        if kind == "error":
            _terminate(workers)
            raise ValueError(payload)
        if kind != "ok":
            _terminate(workers)
            raise RuntimeError(f"a share of the group failed in its worker process: {payload}")
        for j, result in zip(share, payload, strict=True):
            results[j] = result
    if stopped:
        for result in results:
            result.interrupted = True
    return results


def _terminate(workers: list) -> None:
    """SIGTERM to the workers still running (their training stops between two steps and answers)."""
    for _, process in workers:
        if process.is_alive():
            os.kill(process.pid, signal.SIGTERM)
