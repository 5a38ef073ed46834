"""A run as one ``.zip`` file, the way Stable-Baselines3 saves a model: what ``SOMQ.save("model.zip")``
writes and ``SOMQ.load`` and ``somarm evaluate`` read.

The archive holds a run folder's files at its top level (``config.json``, ``learner.npz``,
``curves.npz``, ``summary.json``), without the figures, which a folder keeps. Reading it unpacks
those files, and only those, into a temporary folder that is removed afterwards.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import tempfile
import zipfile
import zlib
from collections.abc import Iterator
from pathlib import Path

__all__ = ["MEMBERS", "is_archive", "pack", "unpacked"]

#: The files of a run folder that an archive holds (what ``load`` and ``learn`` read back).
MEMBERS = ("config.json", "learner.npz", "curves.npz", "summary.json")


def is_archive(path: str | Path) -> bool:
    """Whether ``path`` is a zip file (rather than a run folder)."""
    path = Path(path)
    return path.is_file() and zipfile.is_zipfile(path)


def pack(folder: Path, path: Path) -> Path:
    """Write ``folder``'s ``MEMBERS`` into the zip file ``path`` (its parent folders made), whole or not
    at all: written under a temporary name beside it and renamed, so an earlier file stays until then.

    Raises:
      ValueError: ``path`` is a folder, or the file cannot be written (one line).
    """
    if path.is_dir():
        raise ValueError(f"{path} is a folder; give a file name ending in .zip, or the folder's own name")
    temporary = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        with zipfile.ZipFile(temporary, "w", compression=zipfile.ZIP_DEFLATED) as archive:
            for name in MEMBERS:
                if (folder / name).is_file():
                    archive.write(folder / name, arcname=name)
        os.replace(temporary, path)
    except OSError as exc:
        with contextlib.suppress(OSError):
            temporary.unlink()
        raise ValueError(f"cannot write {path}: {exc.strerror or exc}") from None
    return path


@contextlib.contextmanager
def unpacked(path: Path) -> Iterator[Path]:
    """A temporary folder holding the ``MEMBERS`` found in the zip file ``path`` (other entries are left
    in the archive), removed on leaving.

    Raises:
      ValueError: the archive cannot be read (one line).
    """
    folder = Path(tempfile.mkdtemp(prefix="somarm-zip-"))
    try:
        try:
            with zipfile.ZipFile(path) as archive:
                for name in set(archive.namelist()) & set(MEMBERS):  # flat names only: nothing lands elsewhere
                    with archive.open(name) as source, open(folder / name, "wb") as target:
                        shutil.copyfileobj(source, target)
        except (OSError, zipfile.BadZipFile, EOFError, zlib.error) as exc:
            raise ValueError(f"cannot read {path}: {exc}") from None
        yield folder
    finally:
        shutil.rmtree(folder, ignore_errors=True)
