"""The status of work spread over worker processes or a cluster: what is done, what runs, how far, the time left.

``somarm reproduce --jobs N`` (its experiments, whose workers send their training parts' progress
through ``somarm.run.progress.report_to``) and ``--engine ray`` (``somarm.cluster``: experiments, or
a comparison's learner-seed units) show it in one status line on stderr:

    [######......] 3/9 done, 2 running: more_inputs ~41% (fig24 1200/4000), beyond ~12% | 4:05, ~6 min left

On a terminal the line is a bar redrawn in place (tqdm, which the base install already has through
dm_control: it fits the line to the terminal's width, limits the redraws and prints the events above
the bar without breaking it). Into a file or a pipe (a CI log) it writes plain lines instead: the
events (an experiment started or finished) as they happen and the status line once a minute.

A piece of work's fraction and the time left are estimates, marked with ``~``: a piece does not
know its own length beforehand, so each has an expected duration (for the reproduction's
experiments, the measured ones of ``somarm/reproduce/durations.json``; for a
cluster's units, the mean of the finished units of the same kind). Scaled by how this run has kept
to them so far (the finished pieces' measured over expected seconds, or a running one's that is
already past its expected time), they give the running pieces' fractions and, placed on the free
workers in order, the time left. What the training part under way reports (its steps done of its
total) is exact.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import sys
import time
from typing import TextIO

__all__ = ["Status", "time_left"]

#: Away from a terminal: one status line per this many seconds.
LOG_PERIOD_S = 60.0
#: On a terminal: redraw at most this often (seconds).
DRAW_PERIOD_S = 0.5
#: The longest training part label shown (longer ones are cut).
_LABEL = 16


def time_left(remaining_running: list[float], waiting: list[float], workers: int) -> float:
    """Seconds until the last experiment ends: the waiting ones (in their order) each go to the worker
    that is free first, the running ones holding theirs for their remaining seconds."""
    free = sorted([*remaining_running, *[0.0] * max(0, workers - len(remaining_running))])
    for seconds in waiting:
        free[0] += seconds
        free.sort()
    return max(free, default=0.0)


def _clock(seconds: float) -> str:
    seconds = max(0, int(round(seconds)))
    return f"{seconds // 3600}:{seconds // 60 % 60:02d}:{seconds % 60:02d}" if seconds >= 3600 else \
        f"{seconds // 60}:{seconds % 60:02d}"


def _about(seconds: float) -> str:
    """A time left in words: ``~40 s``, ``~6 min``, ``~1.5 h``."""
    if seconds < 90:
        return f"~{max(5, round(seconds / 5) * 5)} s"
    if seconds < 5400:
        return f"~{round(seconds / 60)} min"
    return f"~{seconds / 3600:.1f} h"


class Status:
    """The status of pieces of work (experiments, units) run elsewhere, shown on ``stream`` (stderr by default).

    Args:
      names: the pieces, in the order they will start.
      workers: how many run at once.
      expected: expected seconds by piece; one left out makes the time left unknown (``expected`` may
        be updated as the run learns more).
      enabled: draw the status (bar or periodic lines); the events are written either way.
    """

    def __init__(self, names: list[str], *, workers: int, expected: dict[str, float], stream: TextIO | None = None,
                 enabled: bool = True) -> None:
        self.names = list(names)
        self.workers = workers
        self.expected = dict(expected)
        self.stream = stream if stream is not None else sys.stderr
        self.enabled = enabled
        self.start = time.monotonic()
        self.began: dict[str, float] = {}  # running experiment -> when it started
        self.took: dict[str, float] = {}  # finished experiment -> its seconds
        self.lost: list[str] = []  # the pieces that failed
        self.part: dict[str, tuple[str, int, int]] = {}  # running experiment -> (label, step, total) of its training
        self.terminal = _is_terminal(self.stream)
        self._bar = None
        self._last_line = time.monotonic()
        self._last_draw = -float("inf")
        if self.enabled and self.terminal:
            from tqdm import tqdm

            self._bar = tqdm(total=1000, file=self.stream, bar_format="{bar:20}| {desc}", ncols=self.width(),
                             leave=False, mininterval=0.0)

    # Events -----------------------------------------------------------------------------------
    def started(self, name: str, where: str) -> None:
        """Piece ``name`` started ``where`` (``"in process 123"``, ``"on the cluster"``)."""
        self.began[name] = time.monotonic()
        self.say(f"{name}: started {where}")

    def progress(self, name: str, label: str, step: int, total: int) -> None:
        """A running experiment's training part ``label`` is at ``step`` of ``total``."""
        self.part[name] = (label, step, total)

    def finished(self, name: str) -> float:
        """Piece ``name`` ended (its own line is written by the caller, through ``say``); its seconds."""
        self.took[name] = time.monotonic() - self.began.pop(name, self.start)
        self.part.pop(name, None)
        return self.took[name]

    def failed(self, name: str) -> None:
        """Piece ``name`` failed (the caller says why, through ``say``)."""
        self.began.pop(name, None)
        self.part.pop(name, None)
        self.lost.append(name)

    def say(self, line: str) -> None:
        """Write an event line (above the bar on a terminal)."""
        with self.above():
            print(line, file=self.stream, flush=True)

    @contextlib.contextmanager
    def above(self):
        """Anything written to the stream inside goes above the bar (which is redrawn after)."""
        if self._bar is None:
            yield
            return
        self._bar.clear()
        try:
            yield
        finally:
            self.draw(force=True)

    def close(self) -> None:
        """Take the bar away (the events stay)."""
        if self._bar is not None:
            self._bar.close()
            self._bar = None

    # The status line ----------------------------------------------------------------------------
    def pace(self) -> float:
        """Measured over expected seconds so far (1 until something says otherwise)."""
        done = [n for n in self.took if n in self.expected]
        if done:
            return sum(self.took[n] for n in done) / max(1e-9, sum(self.expected[n] for n in done))
        now = time.monotonic()
        over = [(now - t) / self.expected[n] for n, t in self.began.items() if self.expected.get(n)]
        return max([1.0, *over])

    def fractions(self) -> dict[str, float]:
        """Each running experiment's estimated fraction done (below 1 while it runs; NaN without a measure)."""
        now, pace = time.monotonic(), self.pace()
        return {n: min(0.99, (now - t) / (pace * self.expected[n])) if self.expected.get(n) else float("nan")
                for n, t in self.began.items()}

    def seconds_left(self) -> float | None:
        """Estimated seconds until every experiment has ended; None when one has no expected duration."""
        pending = [n for n in self.names if n not in self.took and n not in self.lost]
        if any(n not in self.expected for n in pending):
            return None
        now, pace = time.monotonic(), self.pace()
        running = [max(0.0, pace * self.expected[n] - (now - t)) for n, t in self.began.items()]
        waiting = [pace * self.expected[n] for n in pending if n not in self.began]
        return time_left(running, waiting, self.workers)

    def line(self) -> str:
        """The status line (without the bar)."""
        fractions = self.fractions()
        running = []
        for name in self.began:
            share = fractions[name]
            text = name + ("" if share != share else f" ~{share:.0%}")
            if name in self.part:  # its training part under way: exact
                label, step, total = self.part[name]
                label = label if len(label) <= _LABEL else label[:_LABEL - 1] + "…"
                text += f" ({label + ' ' if label else ''}{step}/{total})"
            running.append(text)
        left = self.seconds_left()
        if len(self.took) + len(self.lost) == len(self.names):
            left_text = "all done"
        elif left is None:
            left_text = "time left unknown (no measured duration)"
        else:
            left_text = f"{_about(left)} left"
        return (f"{len(self.took)}/{len(self.names)} done, {len(self.began)} running"
                + (f", {len(self.lost)} failed" if self.lost else "")
                + (": " + ", ".join(running) if running else "")
                + f" | {_clock(time.monotonic() - self.start)}, {left_text}")

    def width(self) -> int:
        """The terminal's width in columns (80 when it tells none, as a new pseudo-terminal may)."""
        try:
            columns = os.get_terminal_size(self.stream.fileno()).columns
        except (AttributeError, ValueError, OSError):
            columns = 0
        return columns if columns > 0 else shutil.get_terminal_size((80, 24)).columns

    def done_share(self) -> float:
        """The estimated share of the whole run done, by expected seconds (by experiments without them)."""
        if any(n not in self.expected for n in self.names):
            return (len(self.took) + len(self.lost)) / max(1, len(self.names))
        fractions = self.fractions()
        total = sum(self.expected[n] for n in self.names)
        done = (sum(self.expected[n] for n in [*self.took, *self.lost])
                + sum(self.expected[n] * fractions[n] for n in self.began))
        return done / max(1e-9, total)

    def draw(self, *, force: bool = False) -> None:
        """Redraw the bar (terminal) or write the status line if a minute has passed (file or pipe)."""
        if not self.enabled:
            return
        now = time.monotonic()
        if self._bar is not None:
            if force or now - self._last_draw >= DRAW_PERIOD_S:
                self._last_draw = now
                self._bar.ncols = self.width()  # the line fits the terminal as it is now
                self._bar.n = round(1000 * self.done_share())
                self._bar.set_description_str(self.line(), refresh=False)
                self._bar.refresh()
        elif force or now - self._last_line >= LOG_PERIOD_S:
            self._last_line = now
            print(self.line(), file=self.stream, flush=True)


def _is_terminal(stream: TextIO) -> bool:
    try:
        return bool(stream.isatty())
    except (AttributeError, ValueError):
        return False
