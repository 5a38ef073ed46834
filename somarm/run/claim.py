"""A folder of results owned by one process at a time, replaced only when the new results are complete.

``claim`` locks the folder (``fcntl.flock`` on ``.somarm.lock`` inside it, released by the kernel
when the process ends, even by SIGKILL), so a second writer is refused at once instead of mixing
its files with the first one's. A folder that already holds files is refused unless ``force``.

What a run wrote is listed in the folder's manifest (``.somarm-manifest.json``), and nothing
else is ever removed or overwritten: a user's own files in the folder stay. A run writes into a
staging folder inside it (``.somarm-new``), so everything there is the run's own, and ``commit``
swaps the new files in at the end: the earlier run's files (those its manifest lists) are moved
aside, the new ones moved in, and the new manifest put in place, which is the moment the new run
becomes the folder's run. A process killed before that moment leaves the earlier run as it was;
the next ``claim`` finds the leftovers and finishes or undoes the swap. New results that would
overwrite a file somarm did not write are kept in a folder of their own instead. A sweep run again
(``resume``) goes on in place.
"""

from __future__ import annotations

import fcntl
import json
import os
import shutil
from dataclasses import dataclass
from pathlib import Path

from somarm.io import make_folder, refuse_links

__all__ = ["LOCK_NAME", "MANIFEST_NAME", "FolderClaim", "claim", "writer_of"]

LOCK_NAME = ".somarm.lock"
MANIFEST_NAME = ".somarm-manifest.json"
_STAGING = ".somarm-new"
_ASIDE = ".somarm-old"
_OURS = {LOCK_NAME, MANIFEST_NAME, _STAGING, _ASIDE}


def _listed(folder: Path) -> list[str]:
    """The files a folder's manifest lists (relative paths), or none where it has no readable one."""
    try:
        data = json.loads((folder / MANIFEST_NAME).read_text())
        files = data["files"] if isinstance(data, dict) else None
    except (OSError, UnicodeDecodeError, ValueError, KeyError, RecursionError):
        return []
    if not isinstance(files, list):
        return []
    return [f for f in files if isinstance(f, str) and f and not f.startswith(("/", ".somarm")) and ".." not in f]


def _files_under(root: Path) -> list[str]:
    """Every file under ``root`` (relative paths, sorted), leaving out the folder's own bookkeeping."""
    return sorted(str(p.relative_to(root)) for p in root.rglob("*")
                  if p.is_file() and p.relative_to(root).parts[0] not in _OURS)


def _write_manifest(path: Path, files: list[str]) -> None:
    tmp = path.with_name(path.name + ".tmp")
    tmp.unlink(missing_ok=True)  # a link planted there is removed, never written through
    tmp.write_text(json.dumps({"files": files}, indent=1) + "\n")
    os.replace(tmp, path)


def _move(src: Path, dst: Path, folder: Path) -> None:
    """Rename ``src`` to ``dst`` inside ``folder``; a link at ``dst`` is replaced, a link standing for one of
    ``dst``'s folders refused (``OSError``)."""
    try:
        refuse_links(src, within=folder)
        make_folder(dst.parent, within=folder)
    except ValueError as exc:
        raise OSError(str(exc)) from None
    os.replace(src, dst)


def _prune_empty(folder: Path, files: list[str]) -> None:
    """Remove the folders that held ``files`` where they are now empty (never ``folder`` itself)."""
    parents = sorted({p for f in files for p in Path(f).parents if p != Path(".")}, key=lambda p: -len(p.parts))
    for parent in parents:
        try:
            (folder / parent).rmdir()
        except OSError:  # not empty (a user's file is there) or gone
            pass


def _recover(folder: Path) -> None:
    """Finish or undo a swap that a killed process left, and drop an unfinished staging folder."""
    aside, staging = folder / _ASIDE, folder / _STAGING
    for ours in (aside, staging):
        if ours.is_symlink():  # not somarm's: a link there is removed, never followed
            ours.unlink()
    if aside.is_dir():
        if (staging / MANIFEST_NAME).is_file():  # the new manifest never moved in: undo
            for name in _listed(staging):
                if not (staging / name).exists():  # moved in already: take it out again
                    (folder / name).unlink(missing_ok=True)
            for name in _files_under(aside):
                _move(aside / name, folder / name, folder)
        shutil.rmtree(aside)
    if staging.is_dir():
        shutil.rmtree(staging)


@dataclass
class FolderClaim:
    """A locked folder. Write into ``path``, then ``commit``; ``release`` (or process exit) unlocks.

    Attributes:
      folder: the folder.
      created: True if ``claim`` made it (so a caller that gives up can remove it again).
      staged: True while the results go to the staging folder (every run but a resumed one).
      replacing: True if the folder held earlier results, which complete new ones replace.
    """

    folder: Path
    created: bool
    staged: bool = False
    replacing: bool = False
    _fd: int | None = None
    _before: frozenset[str] = frozenset()  #: files already there when a run resumed in place

    @property
    def path(self) -> Path:
        """Where this run writes its files until ``commit``."""
        return self.folder / _STAGING if self.staged else self.folder

    def commit(self) -> None:
        """Make what was written in ``path`` the folder's results, and list it in the manifest.

        For a staged run the earlier run's listed files are replaced; other files are left alone.

        Raises:
          ValueError: the swap could not be done (the earlier run is then put back).
        """
        if not self.staged:
            # What this run wrote, and what the folder's earlier runs wrote: not a user's file that was there.
            now = _files_under(self.folder)
            listed = set(_listed(self.folder))
            ours = [f for f in now if f not in self._before or f in listed]
            try:
                _write_manifest(self.folder / MANIFEST_NAME, ours)
            except OSError:  # a full disk: unlisted, these files are only ever replaced by name, never removed
                (self.folder / (MANIFEST_NAME + ".tmp")).unlink(missing_ok=True)
            return
        staging, aside = self.path, self.folder / _ASIDE
        new = _files_under(staging)
        listed = set(_listed(self.folder))
        theirs = [f for f in new if (self.folder / f).exists() and f not in listed]
        if theirs:
            self._set_aside_results(theirs)
        try:
            _write_manifest(staging / MANIFEST_NAME, new)
        except OSError as exc:  # a full disk: renames need no room, a manifest does
            (staging / (MANIFEST_NAME + ".tmp")).unlink(missing_ok=True)
            if self.replacing:
                self.discard()
                raise ValueError(f"cannot put the new results in {self.folder}: {exc.strerror or exc}; "
                                 "the earlier results are kept") from None
            for name in new:  # unlisted, they are never removed by a later run, only kept beside
                _move(staging / name, self.folder / name, self.folder)
            shutil.rmtree(staging, ignore_errors=True)
            self.staged = False
            return
        try:
            old = sorted(f for f in listed if (self.folder / f).is_file())  # moved aside, so a failed swap can undo
            for name in old:
                _move(self.folder / name, aside / name, self.folder)
            for name in new:
                _move(staging / name, self.folder / name, self.folder)
            os.replace(staging / MANIFEST_NAME, self.folder / MANIFEST_NAME)  # the new run is the folder's
        except OSError as exc:
            _recover(self.folder)
            raise ValueError(f"cannot put the new results in {self.folder}: {exc.strerror or exc}; "
                             "the earlier results are kept") from None
        shutil.rmtree(aside, ignore_errors=True)
        shutil.rmtree(staging, ignore_errors=True)
        _prune_empty(self.folder, [f for f in old if f not in new])
        self.staged = False

    def _set_aside_results(self, theirs: list[str]) -> None:
        """Keep new results that would overwrite files somarm did not write in a folder of their own."""
        kept = self.folder / f"somarm-results-{os.getpid()}"
        os.replace(self.path, kept)
        self.staged = False
        shown = ", ".join(theirs[:3]) + (", ..." if len(theirs) > 3 else "")
        raise ValueError(f"{self.folder} holds {shown}, which somarm did not write there (its manifest does not list "
                         f"them), so the new results were not put beside them: they are in {kept}; move those "
                         "files away and run again, or give another folder")

    def discard(self) -> None:
        """Drop what a staged run wrote (the earlier results stay); nothing to do for an unstaged one."""
        if self.staged:
            shutil.rmtree(self.path, ignore_errors=True)

    def finish(self, complete: bool) -> None:
        """``commit`` complete results, or incomplete ones where there is no earlier run; keep the
        earlier run whole rather than replace it with incomplete ones (``discard``)."""
        if complete or not self.replacing:
            self.commit()
        else:
            self.discard()

    def release(self, *, remove_if_unused: bool = False) -> None:
        """Unlock; with ``remove_if_unused``, also remove a folder this claim made that holds nothing else."""
        if self._fd is not None:
            os.close(self._fd)  # closing the descriptor releases the flock
            self._fd = None
        if remove_if_unused and self.created:
            try:
                self.discard()
                (self.folder / LOCK_NAME).unlink(missing_ok=True)
                self.folder.rmdir()
            except OSError:  # something else was put there meanwhile: leave it
                pass


def claim(folder: Path, *, force: bool = False, resume: bool = False, flag: str = "--out",
          what: str = "a run") -> FolderClaim:
    """Lock ``folder`` for this process; with ``force`` over earlier results, stage the new ones.

    Args:
      folder: the output folder (made, with its parents, if missing).
      force: replace earlier results (at ``commit``, and only the files somarm wrote there).
      resume: the folder's results are this process's own to go on with (a sweep, a comparison or a
        report run again): write in place, neither refused nor staged, even into a new folder.
      flag: the option that named the folder, for messages.
      what: what the folder holds, for messages (``a run``, ``a report``).

    Returns:
      The claim; write into its ``path``, ``commit`` when the results are complete, keep it until then.

    Raises:
      ValueError: the folder cannot be made or written, is a file, another process holds it, or it
        holds files and ``force`` is false (one line naming the folder and what to do).
    """
    try:
        os.lstat(folder)
        exists = True
    except FileNotFoundError:
        exists = False
    except OSError as exc:  # a name too long for the file system, a loop of links
        shown = str(folder) if len(str(folder)) <= 80 else str(folder)[:77] + "..."
        raise ValueError(f"{flag} {shown} cannot be used: {exc.strerror or exc}; give a shorter folder name") from None
    if exists and not folder.is_dir():
        raise ValueError(f"{flag} {folder} is a file; give a folder (new, or holding {what})")
    created = not folder.exists()
    had_lock = os.path.lexists(folder / LOCK_NAME)
    try:
        folder.mkdir(parents=True, exist_ok=True)
        fd = os.open(folder / LOCK_NAME, os.O_RDWR | os.O_CREAT | os.O_NOFOLLOW, 0o644)
    except OSError as exc:
        _leave_as_found(folder, created, had_lock)
        if (folder / LOCK_NAME).is_symlink():
            raise ValueError(f"{flag} {folder} holds {LOCK_NAME} as a symbolic link, which somarm never writes "
                             "through; remove the link (or give another folder)") from None
        raise ValueError(f"{flag} {folder} is not writable: {exc.strerror or exc}") from None
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError:
        owner = _pid_in(fd)
        os.close(fd)
        raise ValueError(f"{flag} {folder} is being written by another somarm process (pid {owner}); "
                         f"wait for it to finish, or give another {flag}") from None
    held = FolderClaim(folder, created, _fd=fd)
    try:
        os.ftruncate(fd, 0)
        os.pwrite(fd, f"{os.getpid()}\n".encode(), 0)
        _recover(folder)
        existing = sorted(p.name for p in folder.iterdir() if p.name not in _OURS)
        if resume:  # in place from the start, so that what a killed run finished is there to go on with
            if (link := _linked_folder(folder)) is not None:
                raise ValueError(f"{flag} {folder} holds {link}, a symbolic link to a folder, and somarm never writes "
                                 "through a link; remove the link (or give another folder)")
            held._before = frozenset(_files_under(folder))
            return held
        if existing and not force:
            shown = ", ".join(existing[:4]) + (", ..." if len(existing) > 4 else "")
            raise ValueError(f"{flag} {folder} is not empty ({shown}); give --force to replace {what} "
                             f"there, or another {flag}")
        held.replacing = bool(existing)
        held.staged = True
        held.path.mkdir()  # the new results wait here until commit: only what is there is listed as somarm's
    except OSError as exc:
        held.release()
        _leave_as_found(folder, created, had_lock)
        raise ValueError(f"{flag} {folder} is not writable: {exc.strerror or exc}") from None
    except ValueError:
        held.release()
        _leave_as_found(folder, created, had_lock)
        raise
    return held


def _linked_folder(folder: Path) -> Path | None:
    """The first symbolic link to a folder found inside ``folder`` (not followed), or None."""
    for here, dirs, _ in os.walk(folder):
        for name in dirs:
            if os.path.islink(os.path.join(here, name)):
                return Path(here) / name
    return None


def _pid_in(fd: int) -> str:
    """The pid a lock file holds (its writer wrote it there), or ``unknown``."""
    return os.pread(fd, 32, 0).decode(errors="replace").strip() or "unknown"


def writer_of(folder: Path) -> str | None:
    """The pid of the somarm process writing ``folder`` now, or None where none is."""
    try:
        fd = os.open(folder / LOCK_NAME, os.O_RDONLY)
    except OSError:  # no lock file: no process ever claimed it
        return None
    try:
        fcntl.flock(fd, fcntl.LOCK_SH | fcntl.LOCK_NB)
        return None
    except OSError:
        return _pid_in(fd)
    finally:
        os.close(fd)


def _leave_as_found(folder: Path, created: bool, had_lock: bool) -> None:
    """After a refusal: no lock file left in a folder that had none, and no folder that was not there."""
    try:
        if not had_lock:
            (folder / LOCK_NAME).unlink(missing_ok=True)
        if created:
            folder.rmdir()
    except OSError:  # another process holds it, or something else is there now: leave it
        pass
