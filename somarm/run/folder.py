"""The run folder, written and read here alone; a folder is owned by one process at a time.

``write`` and ``load`` are the run folder's format (``learner.npz``, ``config.json``,
``curves.npz``, ``summary.json`` and the figures).

``claim`` locks the folder (``fcntl.flock`` on ``.somarm.lock`` inside it, released by the
kernel when the process ends, even by SIGKILL), so a second writer is refused at once instead
of mixing its files with the first one's. A folder that already holds files is refused unless
``force``; a forced run first removes the files such a run writes (so no figure of the old run
survives next to the new ones) and leaves anything else alone.
"""

from __future__ import annotations

import fcntl
import json
import os
import shutil
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from somarm import __version__
from somarm.io import atomic_save_npz, atomic_write_json
from somarm.protocols import BatchedTask, Learner
from somarm.run.build import make_task
from somarm.run.config import RunConfig
from somarm.run.group import RunResult
from somarm.run.summary import summary

__all__ = ["LOCK_NAME", "RUN_FILES", "REPORT_FILES", "FolderClaim", "claim", "write", "load", "task_for"]

LOCK_NAME = ".somarm.lock"
#: What a run folder holds (``run.write``): removed by a forced run before it starts.
RUN_FILES = ("config.json", "curves.npz", "learner.npz", "summary.json", "*.png")
#: What a reproduction folder holds (``somarm reproduce``).
REPORT_FILES = ("REPORT.md", "claims.json", "figures")


@dataclass
class FolderClaim:
    """A locked folder. ``release`` (or process exit) lets the next writer in.

    Attributes:
      folder: the folder.
      created: True if ``claim`` made it (so a caller that gives up can remove it again).
    """

    folder: Path
    created: bool
    _fd: int | None = None

    def release(self, *, remove_if_unused: bool = False) -> None:
        """Unlock; with ``remove_if_unused``, also remove a folder this claim made that holds nothing else."""
        if self._fd is not None:
            os.close(self._fd)  # closing the descriptor releases the flock
            self._fd = None
        if remove_if_unused and self.created:
            try:
                (self.folder / LOCK_NAME).unlink(missing_ok=True)
                self.folder.rmdir()
            except OSError:  # something else was put there meanwhile: leave it
                pass


def claim(folder: Path, *, force: bool = False, products: tuple[str, ...] = RUN_FILES, flag: str = "--out",
          what: str = "a run") -> FolderClaim:
    """Lock ``folder`` for this process and make sure it holds no earlier results.

    Args:
      folder: the output folder (made, with its parents, if missing).
      force: replace earlier results: remove the files matching ``products`` first.
      products: glob patterns of what such a folder holds (``RUN_FILES``, ``REPORT_FILES``).
      flag: the option that named the folder, for messages.
      what: what the folder holds, for messages (``a run``, ``a report``).

    Returns:
      The claim; keep it until the results are written.

    Raises:
      ValueError: the folder cannot be made or written, another process holds it, or it holds
        files and ``force`` is false (one line naming the folder and what to do).
    """
    created = not folder.exists()
    try:
        folder.mkdir(parents=True, exist_ok=True)
        fd = os.open(folder / LOCK_NAME, os.O_RDWR | os.O_CREAT, 0o644)
    except OSError as exc:
        raise ValueError(f"{flag} {folder} is not writable: {exc.strerror or exc}") from None
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError:
        owner = os.pread(fd, 32, 0).decode(errors="replace").strip() or "unknown"
        os.close(fd)
        raise ValueError(f"{flag} {folder} is being written by another somarm process (pid {owner}); "
                         f"wait for it to finish, or give another {flag}") from None
    held = FolderClaim(folder, created, fd)
    try:
        os.ftruncate(fd, 0)
        os.pwrite(fd, f"{os.getpid()}\n".encode(), 0)
        existing = sorted(p.name for p in folder.iterdir() if p.name != LOCK_NAME)
        if existing and not force:
            shown = ", ".join(existing[:4]) + (", ..." if len(existing) > 4 else "")
            raise ValueError(f"{flag} {folder} is not empty ({shown}); give --force to replace {what} "
                             f"there, or another {flag}")
        if force:
            for pattern in products:
                for path in folder.glob(pattern):
                    shutil.rmtree(path) if path.is_dir() else path.unlink()
    except OSError as exc:
        held.release()
        raise ValueError(f"{flag} {folder} is not writable: {exc.strerror or exc}") from None
    except ValueError:
        held.release()
        raise
    return held


def write(result: RunResult, out_dir: str | Path, *, figures: bool = True,
          extra_summary: dict[str, Any] | None = None) -> Path:
    """Write a run folder: learner.npz, config.json, curves.npz, summary.json, then PNG figures.

    Every file is written atomically, so an interrupted write leaves the previous file or none.
    The most valuable file goes first: with a full disk the trained learner (and the config that
    ``somarm evaluate`` needs beside it) are kept even when the figures no longer fit.

    Raises:
      ValueError: the folder cannot be created, or a file cannot be written (one line naming the
        file and the files already written, which are kept).
    """
    out = Path(out_dir)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise ValueError(f"cannot create output folder {out}: {exc.strerror or exc}") from None
    config = result.config
    data = summary(result, extra_summary)
    steps = [
        ("learner.npz", lambda: result.learner.save(out / "learner.npz")),
        ("config.json", lambda: atomic_write_json(out / "config.json",
                                                  {**config.to_dict(), "somarm_version": __version__})),
        ("curves.npz", lambda: atomic_save_npz(out / "curves.npz", block_means=result.block_means,
                                               block_sq_means=result.block_sq_means, block=config.block,
                                               steps=result.steps, seed=config.seed)),
        ("summary.json", lambda: atomic_write_json(out / "summary.json", data)),
    ]
    if figures and result.steps_done > 0:
        from somarm import plots

        steps.append(("the figures", lambda: plots.run_figures(result, out)))
    written: list[str] = []
    for name, write_file in steps:
        try:
            write_file()
        except ValueError as exc:
            kept = f"kept {', '.join(written)}" if written else "nothing was written"
            raise ValueError(f"{exc} ({kept})") from None
        written.append(name)
    return out


def load(out_dir: str | Path) -> tuple[RunConfig, Learner]:
    """Read a run folder's config and final learner state.

    Raises:
      ValueError: not a run folder, or a damaged ``config.json`` or ``learner.npz``.
    """
    from somarm import learners

    out = Path(out_dir)
    for name in ("config.json", "learner.npz"):
        if not (out / name).is_file():
            raise ValueError(f"{out} is not a run folder: {name} is missing")
    try:
        data = json.loads((out / "config.json").read_text())
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise ValueError(f"{out / 'config.json'} is not readable JSON: {exc}") from None
    if isinstance(data, dict):
        data.pop("somarm_version", None)
    try:
        config = RunConfig.from_dict(data).resolved()  # the same checks as `train` (a seed >= 0, ...)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{out / 'config.json'}: {exc}") from None
    learner = learners.load(out / "learner.npz")
    _check_learner_fits(config, learner, out / "learner.npz")
    return config, learner


def _check_learner_fits(config: RunConfig, learner: Learner, path: Path) -> None:
    """Refuse a learner file that is not the one config.json describes (another kind, task or batch)."""
    where = f"{path} does not belong to {path.parent / 'config.json'}"
    if learner.kind != config.learner:
        raise ValueError(f"{where}: it holds a {learner.kind} learner, the config says {config.learner}")
    if learner.seed != config.seed or learner.trial_ids.tolist() != config.trial_ids_array().tolist():
        raise ValueError(f"{where}: its seed and trials ({learner.seed}, {learner.trial_ids.tolist()}) differ "
                         f"from the config's ({config.seed}, {config.trial_ids_array().tolist()})")
    task = make_task(config)
    for what, ours, theirs in (
        ("observation", (learner.observation_low, learner.observation_high),
         (task.observation_low, task.observation_high)),
        ("action", (learner.action_low, learner.action_high), (task.action_low, task.action_high)),
    ):
        if ours[0].shape != theirs[0].shape or not all(map(np.allclose, ours, theirs)):
            raise ValueError(f"{where}: its {what} bounds are not those of task {config.task!r} "
                             "(a learner of another task?)")


def task_for(config: RunConfig, learner: Learner) -> BatchedTask:
    """The task of a loaded run for all the learner's trials, in the learner's phase (four_goals)."""
    from somarm import tasks

    task = tasks.make(config.task, n_trials=learner.n_trials, seed=config.seed, backend=config.backend,
                      **config.task_params)
    task.set_step(learner.t)
    return task
