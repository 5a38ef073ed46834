"""How a run stops: Ctrl-C (SIGINT), SIGTERM and SIGHUP (a closed terminal), handled here and nowhere else.

SIGHUP is handled as SIGTERM is: wherever "SIGTERM" is said below, SIGHUP does the same.

Training reads a flag between steps (``stop_between_steps``), so a run never stops between a
learner's ``act`` and ``learn``; outside the training loop (``somarm reproduce``, the writing of a
run folder) SIGTERM is made to behave like Ctrl-C (``sigterm_as_interrupt``), so a stopped
command still keeps what it finished. Work whose result may be dropped, such as a greedy evaluation,
is cut short at once (``cut_short_by_signals``), even where the signals are being held back for a write.
"""

from __future__ import annotations

import contextlib
import ctypes
import os
import signal
import sys
import threading
from collections.abc import Callable, Iterator
from typing import TypeVar

__all__ = ["stop_between_steps", "sigterm_as_interrupt", "signals_deferred", "start_deaf_to_ctrl_c",
           "end_with_parent", "cut_short_by_signals"]

T = TypeVar("T")

#: The signals that stop a run: Ctrl-C, SIGTERM, and SIGHUP (the terminal it ran in was closed).
_STOPPING = (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)


class _Cut(BaseException):
    """Raised by the handler of ``cut_short_by_signals`` (a BaseException, as KeyboardInterrupt is, so
    that no ``except Exception`` of the work swallows it)."""


@contextlib.contextmanager
def stop_between_steps() -> Iterator[dict[str, bool]]:
    """Inside, Ctrl-C and SIGTERM only set ``flag["requested"]``, which the loop reads after each step.

    Signals that were being ignored stay ignored; outside the main thread nothing changes (Python
    delivers signals to the main thread only).
    """
    stop = {"requested": False}
    if threading.current_thread() is not threading.main_thread():
        yield stop
        return

    def request(signum, frame):
        stop["requested"] = True

    with _handled_by(request):
        yield stop


@contextlib.contextmanager
def signals_deferred() -> Iterator[dict[str, int]]:
    """Inside, Ctrl-C and SIGTERM are held back; on leaving, the first one held raises KeyboardInterrupt.

    For the writing of results: a second Ctrl-C (or a SIGTERM) right after the one that stopped a
    run waits until the files are written, instead of cutting the writing short. Only SIGKILL is
    not held back. Outside the main thread nothing changes.
    """
    held = {"signal": 0}
    if threading.current_thread() is not threading.main_thread():
        yield held
        return

    def hold(signum, frame):
        held["signal"] = held["signal"] or signum

    with _handled_by(hold):
        yield held
    if held["signal"]:
        raise KeyboardInterrupt


def cut_short_by_signals(work: Callable[[], T]) -> tuple[T | None, int]:
    """``work()``, cut short by the first Ctrl-C or SIGTERM that arrives while it runs.

    Returns ``(work's value, 0)``, or ``(None, the signal)`` when a signal cut it. The signal is then
    handed on to the handler that was there before, as if it had arrived just now: where the signals
    are held back for a write (``signals_deferred``) the command still ends as interrupted once it has
    written, and where Ctrl-C raises ``KeyboardInterrupt`` it is raised here. Signals being ignored
    stay ignored; outside the main thread ``work`` runs as it is.
    """
    if threading.current_thread() is not threading.main_thread():
        return work(), 0
    got = {"signal": 0, "working": True}

    def cut(signum, frame):
        if not got["signal"]:
            got["signal"] = signum
            if got["working"]:  # once the work is over, a signal is only noted (and handed on below)
                raise _Cut

    value = None
    try:
        with _handled_by(cut):
            try:
                value = work()
            finally:
                got["working"] = False
    except _Cut:
        pass
    if got["signal"]:
        signal.raise_signal(got["signal"])
        return None, got["signal"]
    return value, 0


def sigterm_as_interrupt() -> None:
    """From now on SIGTERM and SIGHUP raise ``KeyboardInterrupt`` like Ctrl-C (main thread only)."""

    def handler(signum, frame):
        raise KeyboardInterrupt

    if threading.current_thread() is threading.main_thread():
        signal.signal(signal.SIGTERM, handler)
        if signal.getsignal(signal.SIGHUP) is not signal.SIG_IGN:  # under nohup it stays ignored
            signal.signal(signal.SIGHUP, handler)


def start_deaf_to_ctrl_c(process) -> None:
    """Start a worker ``multiprocessing.Process`` with Ctrl-C ignored from its first instruction on
    (it inherits that): a Ctrl-C at the terminal reaches the parent alone, which stops its workers."""
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        process.start()
    finally:
        signal.signal(signal.SIGINT, previous)


def end_with_parent(parent: int) -> None:
    """In a worker process: receive SIGTERM when the process ``parent`` that started it dies.

    A worker ignores Ctrl-C and relies on its parent to stop it; if the parent is killed outright
    (SIGKILL, a crash), the worker would train on, or write figures into a folder that a new run may
    already own. With this call it gets SIGTERM instead, which stops it the way the parent would
    (between two steps). Linux only (``prctl(PR_SET_PDEATHSIG)``, which fires when the thread that
    started the worker ends: workers are started from the main thread); elsewhere a no-op. A parent
    that died before this call is caught by comparing ``os.getppid()``.
    """
    if sys.platform.startswith("linux"):
        ctypes.CDLL(None, use_errno=True).prctl(1, int(signal.SIGTERM))  # 1 = PR_SET_PDEATHSIG
        if os.getppid() != parent:
            os.kill(os.getpid(), signal.SIGTERM)


@contextlib.contextmanager
def _handled_by(handler) -> Iterator[None]:
    """Inside, SIGINT, SIGTERM and SIGHUP go to ``handler``; signals being ignored stay ignored; restored after."""
    previous = {sig: signal.getsignal(sig) for sig in _STOPPING}
    for sig, old in previous.items():
        if old is not signal.SIG_IGN:
            signal.signal(sig, handler)
    try:
        yield
    finally:
        for sig, old in previous.items():
            signal.signal(sig, old)
