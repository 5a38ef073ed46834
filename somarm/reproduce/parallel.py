"""``somarm reproduce --jobs N``: experiments run at once, in N worker processes.

The experiments of a reproduction share nothing but the output folder (each writes its own
figures), so N of them can run at once on N cores. N worker processes are started fresh
(``spawn``), once: each takes the next experiment, the longest first, whenever it is free (a
process per experiment would pay a few seconds of imports every time). A worker runs its physics
on as many threads as there are cores (while two run the system shares the cores; the last one
left gets them all). It sends back each finished section, and this process alone writes the
report, in the paper's order, after each one. A worker's results equal a run in this process:
every experiment draws from its own seeds. While it trains, a worker sends its training parts'
progress too (``somarm.run.progress.report_to``), which this process shows in one status line
(``somarm.status``), its time left estimated from the experiments' measured durations
(``durations.json``, ``expected_durations``).

Workers start with Ctrl-C ignored, so a Ctrl-C at the terminal (or SIGTERM, which the command
turns into Ctrl-C) reaches this process alone, which then sends every worker SIGTERM: that stops a
worker's training between two steps, as a run in the foreground stops, and the report keeps the
experiments that had finished. A worker that cannot write a figure (a full disk) stops the others
the same way and its one-line error is raised here.
"""

from __future__ import annotations

import json
import multiprocessing
import os
import signal
import sys
import time
from collections.abc import Callable
from multiprocessing.connection import wait
from pathlib import Path

from somarm.reproduce.common import Context, run_experiment
from somarm.reproduce.report import Section
from somarm.run.workers import outcome, start
from somarm.status import Status

__all__ = ["LONGEST_FIRST", "LONGEST_FIRST_QUICK", "expected_durations", "run"]

#: Start order: the experiments that take longest at the paper's counts first, so that the short
#: ones fill the other workers' time (names not listed start last, in the order given).
LONGEST_FIRST = ("more_inputs", "delayed_reward", "beyond", "neighbourhood_q", "throw_maps", "four_goals",
                 "reach2", "reach20", "throw", "peers")
#: The same for ``--quick``, whose run lengths are cut by different factors (the order of durations.json's quick times).
LONGEST_FIRST_QUICK = ("throw_maps", "beyond", "more_inputs", "delayed_reward", "neighbourhood_q", "throw",
                       "four_goals", "reach2", "reach20", "peers")
#: Seconds a stopped worker gets to finish its step and exit before it is killed.
_GRACE_S = 60.0


def expected_durations(quick: bool, n_seeds: int) -> dict[str, float]:
    """Each experiment's expected wall time in seconds: the measured wall times of ``durations.json`` (its
    own note names the machine), times ``n_seeds``; experiments without a measure are left out."""
    measured = json.loads((Path(__file__).with_name("durations.json")).read_text())
    return {name: seconds * n_seeds for name, seconds in measured["quick" if quick else "full"].items()}


def _worker(connection, out: Path, quick: bool, seeds: tuple[int, ...], backend: str, threads: int) -> None:
    """Run the experiments the parent sends, one at a time, until it sends None or hangs up; answer
    each with ``workers.outcome``'s ``(kind, section or message)`` (after anything but "ok" this
    worker ends). SIGTERM, from the parent or at its death, stops the experiment under way."""
    from somarm import tasks
    from somarm.run.progress import report_to
    from somarm.run.stopping import sigterm_as_interrupt

    sigterm_as_interrupt()
    tasks.set_threads(threads)
    # Every training part's progress goes to the parent (the bars themselves stay off in a worker).
    report_to(lambda label, step, total: connection.send(("progress", (label, step, total))))
    try:
        while (experiment := connection.recv()) is not None:
            began = time.perf_counter()
            kind, payload = outcome(lambda experiment=experiment: run_experiment(
                experiment, out, quick=quick, seeds=seeds, progress=False, backend=backend))
            if kind == "ok":
                payload.wall_time_s = time.perf_counter() - began
            connection.send((kind, payload))
            if kind != "ok":
                return
    except (EOFError, KeyboardInterrupt):  # the parent hung up, or stopped this worker while it waited
        return
    except BrokenPipeError:  # the parent died (its death stopped this worker): nobody to answer
        return
    finally:
        connection.close()
    # Told to end with every answer sent and every file written (atomically, closed): leave without
    # the interpreter's teardown, which takes about a second once numba has compiled (the parent
    # waits for it).
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(0)


def run(experiments: dict[str, Callable[[Context], Section]], out: Path, *, jobs: int, quick: bool,
        seeds: tuple[int, ...], backend: str, finished: Callable[[str, Section], None],
        progress: bool = True) -> int:
    """Run ``experiments`` (name -> experiment, module-level functions that a worker imports) in up to
    ``jobs`` worker processes; ``finished(name, section)`` as each ends (what it prints goes above the
    status line). ``progress``: show the status line (a bar on a terminal, a line a minute elsewhere);
    the experiments' start lines are written either way.

    Returns:
      0 when every experiment ran, 130 when interrupted (the finished ones were reported).

    Raises:
      ValueError: a worker's one-line error (its experiment stopped, the others were stopped).
      RuntimeError: a worker crashed (its traceback in the message) or died without an answer.
    """
    context = multiprocessing.get_context("spawn")
    threads = max(1, os.cpu_count() or 1)  # see the module docstring
    order = LONGEST_FIRST_QUICK if quick else LONGEST_FIRST
    waiting = sorted(experiments, key=lambda n: order.index(n) if n in order else len(order))
    workers: list = []  # (connection, process), started once and given one experiment after another
    for i in range(min(jobs, len(waiting))):
        # Not a daemon, for it may share out a long group between processes of its own (somarm.run.split);
        # every way out of this function stops and joins it (``_stop``).
        workers.append(start(context, _worker, (out, quick, seeds, backend, threads), name=f"somarm-worker-{i}",
                             duplex=True))
    idle = list(workers)
    running: dict = {}  # connection -> (name, process)
    status = Status(waiting, workers=len(workers), expected=expected_durations(quick, len(seeds)), enabled=progress)
    try:
        while waiting or running:
            while waiting and idle:
                name = waiting.pop(0)
                connection, process = idle.pop(0)
                connection.send(experiments[name])
                running[connection] = (name, process)
                status.started(name, f"in process {process.pid}")
            for connection in wait(list(running), timeout=_status_period(status)):
                _answer(connection, running, idle, status, finished, more=bool(waiting))
            status.draw()
    except KeyboardInterrupt:
        status.close()
        print("\ninterrupted; the report holds the experiments that finished", file=sys.stderr)
        return 130
    finally:
        status.close()
        _stop(workers)
    return 0


def _answer(connection, running: dict, idle: list, status: Status, finished: Callable[[str, Section], None], *,
            more: bool) -> None:
    """Read one message of a running worker: its progress, or its experiment's end (then the worker is
    idle again if ``more`` experiments wait, else told to end).

    Raises:
      KeyboardInterrupt, ValueError, RuntimeError: as ``run`` (the worker stopped, could not write, or crashed).
    """
    name, process = running[connection]
    try:
        kind, payload = connection.recv()
    except EOFError:
        process.join()
        kind, payload = "crash", f"its process ended without an answer (exit code {process.exitcode})"
    if kind == "progress":
        status.progress(name, *payload)
        return
    del running[connection]
    status.finished(name)
    if kind == "ok":
        if more:
            idle.append((connection, process))
        else:  # nothing left for it: it ends now, beside the others' last experiments
            connection.send(None)
        with status.above():
            finished(name, payload)
    elif kind == "interrupted":
        raise KeyboardInterrupt
    elif kind == "error":
        raise ValueError(f"{payload}; {name} stopped (and the experiments running beside it)")
    else:
        raise RuntimeError(f"experiment {name} failed in its worker process: {payload}")


def _status_period(status: Status) -> float:
    """How long to wait for a worker's message before the status is redrawn (its clock moves on)."""
    return 0.5 if status.terminal else 5.0


def _stop(workers: list) -> None:
    """SIGTERM to every worker still running, then wait for it (kill it after ``_GRACE_S``)."""
    deadline = time.monotonic() + _GRACE_S
    for _, process in workers:
        process.join(0.5)  # a worker told to end is gone by now
        if process.is_alive():
            os.kill(process.pid, signal.SIGTERM)
    for connection, process in workers:
        process.join(max(0.0, deadline - time.monotonic()))
        if process.is_alive():
            process.kill()
            process.join()
        connection.close()
    workers.clear()
