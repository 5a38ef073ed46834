"""Which task names a file may name: a run folder is data, and loading one never imports code.

A ``gym:ID`` task whose id reads ``MODULE:ID`` makes Gymnasium import ``MODULE`` before it looks the
id up, so such a name runs whatever that module holds. The command line and a Python caller may
give it (the user chose the module); a name read from a file (a run folder's ``config.json``) is
held to what loading allows: somarm's own tasks, ``gym:ID`` of an id without a module part (found
only among the registered ids), and ``dmc:DOMAIN-TASK``. The check reads the name alone, before
anything is imported; a name it lets through that names nothing is then refused as on the command line.
"""

from __future__ import annotations

from typing import Any

__all__ = ["check_loadable"]

#: The prefixes of the task names built on Gymnasium (``somarm.tasks.gym_envs``).
_PREFIXES = ("gym:", "dmc:")
#: Longer than any task name: a longer one is shown cut.
_SHOWN = 60


def check_loadable(name: Any, *, where: str) -> str:
    """``name`` if a file may name it as its task; checked without importing anything.

    Args:
      name: the task name read from the file.
      where: the file, for the message.

    Raises:
      ValueError: a name that is not text, or one with a module part (``gym:MODULE:ID``): one line
        naming the file, the name and what a file may name.
    """
    if isinstance(name, str):
        rest = name[4:] if name.startswith(_PREFIXES) else name
        if ":" not in rest and "\n" not in rest:
            return name
    shown = repr(name) if len(repr(name)) <= _SHOWN else repr(name)[:_SHOWN] + "..."
    why = (" (a gym:MODULE:ID name imports MODULE: give it on the command line or in code, never in a file)"
           if isinstance(name, str) and ":" in name[4:] else "")
    raise ValueError(f"{where} names task {shown}, which a file may not name{why}; a file names one of somarm's "
                     "tasks (somarm tasks lists them), gym:ID of a registered Gymnasium id, or dmc:DOMAIN-TASK")
