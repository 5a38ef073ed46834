"""Atomic file writes: a file is either its old self or complete, never half-written, and never
written through a symbolic link.

A link found where a file is written is replaced by the file, so its target is left as it was; a
link standing for a folder inside the folder a writer owns (``within``) is refused in one line.
JSON is written strictly: a value JSON cannot hold (NaN, infinity) is written as ``null`` and named
in the file's ``non_finite`` entry, which ``read_json`` reads back.
"""

from __future__ import annotations

import io
import json
import math
import os
import stat
import tempfile
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["atomic_write_bytes", "atomic_write_text", "atomic_write_json", "atomic_save_npz", "make_folder",
           "refuse_links", "read_json", "strict_json", "NON_FINITE"]

#: The entry of a JSON object written by ``atomic_write_json`` that names its non-finite values:
#: ``{"/learners/somq/error/2/0": "nan", ...}`` (JSON pointers to the nulls that stand for them).
NON_FINITE = "non_finite"

#: The largest JSON file ``read_json`` reads unless told otherwise (a record, a summary, a config).
MAX_JSON_BYTES = 64 * 2**20


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def refuse_links(path: str | os.PathLike, *, within: str | os.PathLike) -> None:
    """Refuse a symbolic link standing for a folder between ``within`` and ``path`` (``within`` itself,
    the user's choice, may be a link).

    Raises:
      ValueError: one line naming the link.
    """
    path, within = Path(path), Path(within)
    try:
        parts = path.parent.relative_to(within).parts
    except ValueError:  # not inside: nothing of ``within`` to guard
        return
    here = within
    for part in parts:
        here = here / part
        if here.is_symlink():
            raise ValueError(f"cannot write {path}: {here} is a symbolic link, and somarm never writes through a "
                             f"link inside {within}; remove the link (or give another folder)")


def make_folder(path: str | os.PathLike, *, within: str | os.PathLike) -> Path:
    """Make folder ``path`` (and its parents) inside ``within``, refusing a link on the way.

    Raises:
      ValueError: a symbolic link or a file stands where a folder goes, or the folder cannot be made
        (one line naming it).
    """
    path = Path(path)
    refuse_links(path / "_", within=within)
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise ValueError(f"cannot make folder {path}: {exc.strerror or exc}") from None
    return path


def atomic_write_bytes(path: str | os.PathLike, data: bytes, *, within: str | os.PathLike | None = None) -> Path:
    """Write ``data`` to ``path`` through a temporary file in the same folder, then rename.

    A symbolic link at ``path`` is replaced by the new file, never followed: its target stays as it was.

    Args:
      path: the file.
      data: its new content.
      within: the folder the writer owns (a run, sweep or comparison folder): a link standing for a
        folder between it and ``path`` is refused.

    Raises:
      ValueError: the folder does not exist or cannot be written, the disk is full, a folder stands at
        ``path``, or a link stands for a folder inside ``within`` (one clear line naming ``path``).
    """
    path = Path(path)
    if within is not None:
        refuse_links(path, within=within)
    try:
        mode = os.lstat(path).st_mode
    except OSError:
        mode = None
    if mode is not None and not (stat.S_ISREG(mode) or stat.S_ISDIR(mode) or stat.S_ISLNK(mode)):
        raise ValueError(f"cannot write {path}: it is not a regular file (a device, a pipe or a socket); "
                         "give a file name")
    folder = path.parent if str(path.parent) else Path(".")
    if not folder.is_dir():
        raise ValueError(f"cannot write {path}: folder {folder} does not exist")
    try:
        fd, tmp = tempfile.mkstemp(prefix=f".{path.name[:200]}.", suffix=".tmp", dir=folder)
    except OSError as exc:
        raise ValueError(f"cannot write {path}: {exc.strerror or exc}") from None
    try:
        # mkstemp makes the file 0600; give it the mode a plain open() would (0666 less the umask).
        os.chmod(tmp, 0o666 & ~_umask())
        with os.fdopen(fd, "wb") as handle:
            handle.write(data)
            handle.flush()
            os.fsync(handle.fileno())
        os.replace(tmp, path)  # a rename replaces a link itself, not the file it names
    except BaseException as exc:
        # Ctrl-C or a full disk: leave the old file (if any) and no stray temporary.
        try:
            os.unlink(tmp)
        except FileNotFoundError:
            pass
        if isinstance(exc, OSError):  # a full disk, a folder in the way: one line naming the file
            raise ValueError(f"cannot write {path}: {exc.strerror or exc}") from None
        raise
    return path


def atomic_write_text(path: str | os.PathLike, text: str, *, within: str | os.PathLike | None = None) -> Path:
    """Write UTF-8 text atomically (see ``atomic_write_bytes``)."""
    return atomic_write_bytes(path, text.encode("utf-8"), within=within)


def strict_json(obj: Any) -> tuple[Any, dict[str, str]]:
    """``obj`` with every non-finite float replaced by None, and where they stood (JSON pointers to
    ``"nan"``, ``"inf"`` or ``"-inf"``)."""
    where: dict[str, str] = {}

    def clean(value: Any, pointer: str) -> Any:
        if isinstance(value, (float, np.floating)):
            if math.isfinite(value):
                return float(value) if isinstance(value, np.floating) else value
            where[pointer] = "nan" if math.isnan(value) else ("inf" if value > 0 else "-inf")
            return None
        if isinstance(value, dict):
            return {k: clean(v, f"{pointer}/{_escape(str(k))}") for k, v in value.items()}
        if isinstance(value, (list, tuple)):
            return [clean(v, f"{pointer}/{i}") for i, v in enumerate(value)]
        return value

    return clean(obj, ""), where


def _escape(key: str) -> str:
    return key.replace("~", "~0").replace("/", "~1")


def atomic_write_json(path: str | os.PathLike, obj: Any, *, within: str | os.PathLike | None = None) -> Path:
    """Write ``obj`` as indented, strict JSON atomically (see ``atomic_write_bytes``).

    A non-finite value is written as null; in an object, its ``non_finite`` entry names each one
    (``read_json`` puts them back).
    """
    clean, where = strict_json(obj)
    if where and isinstance(clean, dict):
        clean[NON_FINITE] = where
    return atomic_write_text(path, json.dumps(clean, indent=2, sort_keys=True, allow_nan=False) + "\n",
                             within=within)


def read_json(path: str | os.PathLike, *, max_bytes: int = MAX_JSON_BYTES, follow_links: bool = False) -> Any:
    """Read a JSON file somarm wrote, strictly: a regular file (not a device or a pipe; with
    ``follow_links`` false, not a link either) of at most
    ``max_bytes``, nested no deeper than Python's recursion limit, with its ``non_finite`` values put back.

    Raises:
      ValueError: one line naming the file and what is wrong with it.
    """
    path = Path(path)
    try:
        info = os.stat(path) if follow_links else os.lstat(path)
        if stat.S_ISLNK(info.st_mode):
            raise ValueError(f"{path} is a symbolic link, not a file somarm wrote")
        if not stat.S_ISREG(info.st_mode):
            raise ValueError(f"{path} is not a regular file")
        if info.st_size > max_bytes:
            raise ValueError(f"{path} holds {info.st_size} bytes, more than the {max_bytes} a somarm file has")
        data = json.loads(path.read_bytes().decode("utf-8"),
                          parse_constant=lambda name: _refuse_constant(path, name))
    except OSError as exc:
        raise ValueError(f"{path} cannot be read: {exc.strerror or exc}") from None
    except UnicodeDecodeError:
        raise ValueError(f"{path} is not UTF-8 text") from None
    except json.JSONDecodeError as exc:
        raise ValueError(f"{path} is not readable JSON: {exc}") from None
    except RecursionError:
        raise ValueError(f"{path} is nested too deeply to be a file somarm wrote") from None
    if isinstance(data, dict) and isinstance(flags := data.get(NON_FINITE), dict):
        del data[NON_FINITE]
        for pointer, what in flags.items():
            _put_back(data, pointer, what)
    return data


def _refuse_constant(path: Path, name: str):
    raise ValueError(f"{path} holds {name}, which is not JSON")


def _put_back(data: Any, pointer: str, what: Any) -> None:
    """Set the null at JSON ``pointer`` in ``data`` to float ``what`` ("nan", "inf", "-inf"); ignore a bad flag."""
    if what not in ("nan", "inf", "-inf") or not isinstance(pointer, str) or not pointer.startswith("/"):
        return
    keys = [k.replace("~1", "/").replace("~0", "~") for k in pointer[1:].split("/")]
    here = data
    try:
        for key in keys[:-1]:
            here = here[int(key)] if isinstance(here, list) else here[key]
        last = int(keys[-1]) if isinstance(here, list) else keys[-1]
        if here[last] is None:
            here[last] = float(what)
    except (KeyError, IndexError, ValueError, TypeError):
        return


def atomic_save_npz(path: str | os.PathLike, *, within: str | os.PathLike | None = None, **arrays: Any) -> Path:
    """Save arrays as a compressed ``.npz`` atomically (see ``atomic_write_bytes``)."""
    buffer = io.BytesIO()
    np.savez_compressed(buffer, **arrays)
    return atomic_write_bytes(path, buffer.getvalue(), within=within)
