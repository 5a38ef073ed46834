"""Signals: work cut short by the first Ctrl-C or SIGTERM, the signal then handed on to the handler before."""

import os
import signal
import time

import pytest

from somarm.run.stopping import cut_short_by_signals, signals_deferred


def _signalled(sig):
    def work():
        os.kill(os.getpid(), sig)
        time.sleep(5)  # the signal cuts this short
        return "finished"
    return work


def test_work_without_a_signal_returns_its_value():
    assert cut_short_by_signals(lambda: 42) == (42, 0)


def test_a_signal_cuts_the_work_short_and_reaches_the_handler_that_was_there_before():
    seen = []
    previous = signal.signal(signal.SIGTERM, lambda signum, frame: seen.append(signum))
    try:
        started = time.perf_counter()
        assert cut_short_by_signals(_signalled(signal.SIGTERM)) == (None, signal.SIGTERM)
        assert time.perf_counter() - started < 4 and seen == [signal.SIGTERM]
    finally:
        signal.signal(signal.SIGTERM, previous)


def test_ctrl_c_held_back_for_a_write_cuts_the_work_and_ends_the_write_as_interrupted():
    written = []
    with pytest.raises(KeyboardInterrupt):
        with signals_deferred():
            value, sig = cut_short_by_signals(_signalled(signal.SIGINT))
            written.append((value, sig))  # the write still happens
    assert written == [(None, signal.SIGINT)]


def test_ctrl_c_outside_a_write_raises_keyboard_interrupt_as_before():
    with pytest.raises(KeyboardInterrupt):
        cut_short_by_signals(_signalled(signal.SIGINT))
