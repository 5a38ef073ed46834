"""Folder names made from task and learner names: every character a file system, scp, rsync and tar take.

A task name may hold characters that a folder name should not: ``gym:Pendulum-v1`` has a colon
(invalid on Windows, a host separator to scp and rsync, a remote archive to tar), and a Gymnasium
id may hold a slash (``ALE/Pong-v5``). ``folder_part`` keeps letters, digits, ``.``, ``_``, ``+`` and
``-`` and writes ``-`` for every other character, so ``gym:Pendulum-v1`` becomes
``gym-Pendulum-v1``. Only new folders are named so: a run is read from whatever folder it is in
(its task is read from its ``config.json``, never from the folder's name).
"""

from __future__ import annotations

import re

__all__ = ["folder_part", "run_folder"]

_UNSAFE = re.compile(r"[^A-Za-z0-9._+-]")


def folder_part(name: str) -> str:
    """``name`` as part of a folder name: ``gym:Pendulum-v1`` -> ``gym-Pendulum-v1``,
    ``dmc:cartpole-balance`` -> ``dmc-cartpole-balance``; a name without such characters is kept."""
    return _UNSAFE.sub("-", name)


def run_folder(task: str, learner: str, seed: int) -> str:
    """The default folder of a run under ``runs/``: ``TASK__LEARNER__seedS`` (``reach2__somq__seed0``,
    ``gym-Pendulum-v1__somq__seed0``)."""
    return f"{folder_part(task)}__{folder_part(learner)}__seed{seed}"
