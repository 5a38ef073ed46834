"""The terminal as a side channel: a standard stream that cannot be written never costs a run.

Progress lines and messages go to stdout and stderr, which a user may have pointed at a pipe that
closes early (``somarm train ... 2>&1 | head -1``), a full device (``2>/dev/full``) or a closed
descriptor. ``guard_standard_streams`` wraps both: the first write or flush that fails points the
stream's descriptor at ``/dev/null`` (so the interpreter's own last flush, and any process started
later, write there quietly too), and what cannot be shown is dropped. The run goes on and writes
its files; its exit status is unchanged.
"""

from __future__ import annotations

import os
import sys
from typing import TextIO

__all__ = ["guard_standard_streams", "GuardedStream"]


class GuardedStream:
    """A text stream whose writes and flushes never raise ``OSError``; everything else is the stream's.

    Args:
      stream: the stream to guard (``sys.stdout``, ``sys.stderr``).
    """

    def __init__(self, stream: TextIO) -> None:
        self._stream = stream
        self.dropped = False  #: True once a write failed: from then on the stream writes to /dev/null
        self.reason = ""  #: why the first write failed (``No space left on device``, ``Broken pipe``)

    def write(self, text: str) -> int:
        try:
            return self._stream.write(text)
        except (OSError, ValueError) as exc:  # EPIPE, ENOSPC, EBADF; ValueError: written after close
            self._drop(exc)
            return len(text)

    def flush(self) -> None:
        try:
            self._stream.flush()
        except (OSError, ValueError) as exc:
            self._drop(exc)

    def _drop(self, exc: BaseException | None = None) -> None:
        """Point the descriptor at /dev/null and flush what is buffered there."""
        self.dropped = True
        if exc is not None and not self.reason:
            self.reason = getattr(exc, "strerror", None) or str(exc) or type(exc).__name__
        try:
            fd = self._stream.fileno()
            null = os.open(os.devnull, os.O_WRONLY)
            os.dup2(null, fd)
            os.close(null)
            self._stream.flush()
        except (OSError, ValueError, AttributeError):  # no descriptor (a closed or in-memory stream)
            pass

    def __getattr__(self, name: str):
        return getattr(self._stream, name)


def guard_standard_streams() -> None:
    """Wrap ``sys.stdout`` and ``sys.stderr`` in ``GuardedStream`` (once; a no-op when already guarded)."""
    for name in ("stdout", "stderr"):
        stream = getattr(sys, name)
        if stream is None:  # started with the descriptor closed (`2>&-`): what would go there is dropped
            stream = open(os.devnull, "w")  # noqa: SIM115 - lives as long as the process
        if not isinstance(stream, GuardedStream):
            setattr(sys, name, GuardedStream(stream))
