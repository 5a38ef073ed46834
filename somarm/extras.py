"""The optional extras (``gym``, ``peers``, ``sweep``, ``test``): what a missing one raises, and the
install command that works for how somarm itself was installed.

A clone installed editable (``pip install -e .``) gets its extras with ``pip install -e "CLONE[gym]"``;
an installed wheel with ``pip install 'somarm[gym]'``. Which of the two holds is read from the
distribution's metadata (PEP 610's ``direct_url.json``: ``dir_info.editable``); a source tree run
without installing (``PYTHONPATH``) counts as a clone. The ``peers`` extra pulls torch, whose plain
resolve on Linux is a multi-GB CUDA build: its command installs torch's CPU build first, as
``docs/install.md`` explains.
"""

from __future__ import annotations

import json
from pathlib import Path
from urllib.parse import unquote, urlparse

__all__ = ["MissingExtra", "TORCH_CPU", "install_command", "missing"]

#: The CPU build of torch, installed before the ``peers`` extra (the README's test command does the same).
TORCH_CPU = "pip install torch==2.13.0 --extra-index-url https://download.pytorch.org/whl/cpu"
#: The extras whose packages include torch.
_WITH_TORCH = ("peers",)


class MissingExtra(ImportError, ValueError):
    """An optional extra is not installed. An ``ImportError``, as Python users expect of a missing
    dependency; also a ``ValueError``, so that the command line reports it in its one line."""


def _clone() -> Path | None:
    """The source tree somarm runs from when it is a clone (installed editable, or run from its tree
    without installing), None when it is an installed wheel."""
    from importlib import metadata

    for dist in metadata.distributions(name="somarm"):
        try:
            direct = json.loads(dist.read_text("direct_url.json") or "{}")
        except json.JSONDecodeError:
            continue
        info = direct.get("dir_info") if isinstance(direct, dict) else None
        if isinstance(info, dict) and info.get("editable"):
            url = urlparse(str(direct.get("url", "")))
            if url.scheme == "file" and url.path:
                return Path(unquote(url.path))
    tree = Path(__file__).resolve().parent.parent  # a wheel's somarm sits in site-packages, with no pyproject.toml
    return tree if (tree / "pyproject.toml").is_file() else None


def install_command(extra: str) -> str:
    """The shell command that installs ``extra`` for this installation of somarm (torch's CPU build
    first for the extras that pull torch)."""
    clone = _clone()
    command = f'pip install -e "{clone}[{extra}]"' if clone is not None else f"pip install 'somarm[{extra}]'"
    if extra in _WITH_TORCH:
        return f"{TORCH_CPU} && {command} (torch's CPU build first: see docs/install.md)"
    return command


def missing(extra: str, what: str) -> MissingExtra:
    """The error for a missing extra: ``raise missing("gym", "gym: tasks need gymnasium")``.

    Args:
      extra: the extra's name in ``pyproject.toml``.
      what: what needs it and which package is missing, said first.
    """
    return MissingExtra(f"{what}: {install_command(extra)}")
