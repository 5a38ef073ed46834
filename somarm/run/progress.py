"""A progress display for headless training (no dependency, stderr only).

On a terminal it is one line redrawn in place (carriage returns). Into a file or a pipe (a CI
log, ``2> log``) carriage returns would pile up, so there it writes plain lines instead: the first
update (the run has started), then one at each tenth of the run or each minute, whichever comes
first, and the final line once.

In a worker process of ``somarm reproduce --jobs`` nothing is drawn: ``report_to`` hands every
bar's step to the parent instead (``somarm.status`` shows it), whether or not the bar
itself is enabled.
"""

from __future__ import annotations

import math
import sys
import time
from collections.abc import Callable
from typing import TextIO

__all__ = ["Measures", "Progress", "end_line", "report_to"]

#: Away from a terminal: one line per this share of the run, or per this many seconds.
_LOG_SHARE = 0.1
_LOG_PERIOD_S = 60.0
#: Seconds between two reports to ``report_to``'s reporter (the first and last always go).
REPORT_PERIOD_S = 1.0

#: Where every bar of this process reports ``(label, step, total)``, if anywhere (``report_to``).
_reporter: Callable[[str, int, int], None] | None = None


def report_to(reporter: Callable[[str, int, int], None] | None) -> None:
    """Hand every bar's progress in this process to ``reporter(label, step, total)``, at most once per
    ``REPORT_PERIOD_S`` per bar (its first and last step always); None stops it."""
    global _reporter
    _reporter = reporter


#: The bar whose line is open on a terminal (drawn without its newline yet), if any.
_open_bar: Progress | None = None


def end_line() -> None:
    """End an open progress line, so that a message printed next starts on a line of its own."""
    global _open_bar
    if _open_bar is not None:
        _open_bar.stream.write("\n")
        _open_bar.stream.flush()
        _open_bar = None


def _is_terminal(stream: TextIO) -> bool:
    try:
        return bool(stream.isatty())
    except (AttributeError, ValueError):  # no isatty, or a closed stream
        return False


#: What a bar shows beside its steps: a single value is the mean reward of the last block; a dict names
#: its values (``{"mean return, last 100 episodes": -150.2}``), one per scale of reward.
Measures = float | dict[str, float]

#: The name of a single value: the last block's mean, which summary.json's ``final_mean_reward`` (the mean
#: over a final window of several blocks) is not, so the two are told apart by name.
BLOCK_MEAN = "mean reward, last block"


def _measures_text(measures: Measures) -> str:
    named = {BLOCK_MEAN: measures} if not isinstance(measures, dict) else measures
    return ", ".join(f"{name} {value:+.4f}" if math.isfinite(value) else f"{name}    -   "  # none measured yet
                     for name, value in named.items())


class Progress:
    """Draws ``label [###...] step/total  mean reward, last block -0.123  12.3 s``.

    What follows the steps is ``update``'s measures: the mean reward of the last block (one-step
    tasks), or each named value (an episodic task's mean return over its last finished episodes).

    Args:
      total: number of steps.
      label: text before the bar.
      stream: where to draw (stderr by default); nothing is drawn when ``enabled`` is false.
      rate_hz: on a terminal, redraw at most this many times a second.
    """

    def __init__(
        self,
        total: int,
        *,
        label: str = "",
        stream: TextIO | None = None,
        enabled: bool = True,
        rate_hz: float = 5.0,
    ):
        self.total = max(1, int(total))
        self.label = label
        self.stream = stream if stream is not None else sys.stderr
        self.enabled = enabled
        self.terminal = _is_terminal(self.stream)
        self._period = 1.0 / rate_hz
        self._start = time.perf_counter()
        self._last = -float("inf")
        self._every = max(1, round(self.total * _LOG_SHARE))  # steps between lines in a log
        self._next_mark = self._every
        self._drawn_step: int | None = None
        self._reported = -float("inf")

    def update(self, step: int, mean_reward: Measures, *, force: bool = False) -> None:
        """Redraw if enough time (terminal) or enough of the run (log) has passed, or if ``force``."""
        now = time.perf_counter()
        if _reporter is not None and (force or now - self._reported >= REPORT_PERIOD_S):
            self._reported = now
            _reporter(self.label, step, self.total)
        if not self.enabled:
            return
        if self.terminal:
            if not force and now - self._last < self._period:
                return
        elif not force:
            started = self._drawn_step is not None
            if started and step < self._next_mark and now - self._last < _LOG_PERIOD_S:
                return
            while self._next_mark <= step:
                self._next_mark += self._every
        self._last = now
        self._drawn_step = step
        filled = int(30 * step / self.total)
        bar = "#" * filled + "." * (30 - filled)
        text = f"{self.label} [{bar}] {step}/{self.total}  {_measures_text(mean_reward)}  {now - self._start:6.1f} s"
        self.stream.write(f"\r{text}" if self.terminal else f"{text}\n")
        self.stream.flush()
        if self.terminal:
            global _open_bar
            _open_bar = self

    def close(self, step: int, mean_reward: Measures) -> None:
        """Draw the final state (unless it is already the last line drawn) and end the line."""
        if _reporter is not None:
            _reporter(self.label, step, self.total)
        if not self.enabled:
            return
        if self._drawn_step != step:
            self.update(step, mean_reward, force=True)
        if self.terminal and _open_bar is self:
            end_line()
