"""A one-line progress display for headless training (no dependency, stderr only)."""

from __future__ import annotations

import sys
import time
from typing import TextIO

__all__ = ["Progress"]


class Progress:
    """Redraws ``label [###...] step/total  mean reward -0.123  12.3 s``, at most ``rate_hz`` times a second.

    Args:
      total: number of steps.
      label: text before the bar.
      stream: where to draw (stderr by default); nothing is drawn when ``enabled`` is false.
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
        self._period = 1.0 / rate_hz
        self._start = time.perf_counter()
        self._last = -float("inf")

    def update(self, step: int, mean_reward: float, *, force: bool = False) -> None:
        """Redraw if enough time has passed (or ``force``)."""
        if not self.enabled:
            return
        now = time.perf_counter()
        if not force and now - self._last < self._period:
            return
        self._last = now
        filled = int(30 * step / self.total)
        bar = "#" * filled + "." * (30 - filled)
        self.stream.write(
            f"\r{self.label} [{bar}] {step}/{self.total}  mean reward {mean_reward:+.4f}  "
            f"{now - self._start:6.1f} s"
        )
        self.stream.flush()

    def close(self, step: int, mean_reward: float) -> None:
        """Draw the final state and end the line."""
        if self.enabled:
            self.update(step, mean_reward, force=True)
            self.stream.write("\n")
            self.stream.flush()
