"""Worker processes of this package: how one is started, and how it answers.

``somarm reproduce --jobs`` (``somarm.reproduce.parallel``) and a long lockstep group
(``somarm.run.split``) run work in fresh processes. Both need the same two things, kept here:

- ``start``: the worker starts with Ctrl-C ignored (a Ctrl-C at the terminal reaches the parent
  alone, which stops its workers) and ends with its parent (SIGTERM when the parent dies, so a
  parent killed outright leaves nothing training or writing; ``stopping.end_with_parent``);
- ``outcome``: what the worker sends back, ``("ok", result)`` or how the work failed.
"""

from __future__ import annotations

import os
import signal
import traceback
from collections.abc import Callable

from somarm.console import guard_standard_streams
from somarm.run.stopping import end_with_parent, start_deaf_to_ctrl_c

__all__ = ["start", "outcome"]


def start(context, target: Callable, args: tuple, *, name: str, duplex: bool, daemon: bool = False):
    """Start ``target(connection, *args)`` in a process of the multiprocessing ``context``.

    Returns:
      ``(connection, process)``: this end of the pipe (duplex or towards this process only) and
      the started process.
    """
    mine, theirs = context.Pipe(duplex=duplex)
    process = context.Process(target=_main, args=(os.getpid(), target, theirs, *args), name=name, daemon=daemon)
    start_deaf_to_ctrl_c(process)
    theirs.close()
    return mine, process


def _main(parent: int, target: Callable, connection, *args) -> None:
    end_with_parent(parent)
    guard_standard_streams()  # the parent's stdout/stderr may be a pipe that has closed
    try:
        target(connection, *args)
    except (KeyboardInterrupt, OSError, EOFError):
        pass  # stopped, or the parent is gone while answering: there is nobody to tell
    finally:
        # The work is over: a stop from now on (the parent's death during this process's teardown)
        # ends it quietly instead of raising KeyboardInterrupt inside the interpreter's shutdown.
        signal.signal(signal.SIGTERM, signal.SIG_DFL)
        signal.signal(signal.SIGINT, signal.SIG_IGN)


def outcome(work: Callable[[], object]) -> tuple[str, object]:
    """``("ok", work())``, or how it failed: ``("interrupted", "")`` (Ctrl-C or SIGTERM),
    ``("error", message)`` (a ValueError, a one-line user-facing error such as a full disk) or
    ``("crash", traceback)`` (a bug, shown by the parent)."""
    try:
        return "ok", work()
    except KeyboardInterrupt:
        return "interrupted", ""
    except ValueError as exc:
        return "error", str(exc)
    except BaseException:
        return "crash", traceback.format_exc()
