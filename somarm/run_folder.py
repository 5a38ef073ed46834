"""A folder of results owned by one process at a time: ``somarm train --out`` and ``somarm reproduce --out``.

``claim`` locks the folder (``fcntl.flock`` on ``.somarm.lock`` inside it, released by the
kernel when the process ends, even by SIGKILL), so a second writer is refused at once instead
of mixing its files with the first one's. A folder that already holds files is refused unless
``force``; a forced run first removes the files such a run writes (so no figure of the old run
survives next to the new ones) and leaves anything else alone.
"""

from __future__ import annotations

import fcntl
import os
import shutil
from dataclasses import dataclass
from pathlib import Path

__all__ = ["LOCK_NAME", "RUN_FILES", "REPORT_FILES", "FolderClaim", "claim"]

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
