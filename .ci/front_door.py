"""The README followed as a new user would: its front-door blocks, in order, in a fresh copy of the clone.

The README marks the blocks a newcomer runs first with an HTML comment line starting
``<!-- front door`` just above the block: the install line with the quick reproduction, the
install of the ``gym`` extra, and the Python examples. This script copies the clone's files (those
git knows and those it does not ignore) to a temporary folder and runs each marked block there, as
written: a ``bash`` block with bash (``set -euo pipefail``), a ``python`` block with the fresh
``.venv``'s Python. The README's own ``python3 -m venv .venv`` makes that environment; pip's cache
is kept, so a run after CI's main install downloads nothing again.

Any block that fails ends the run with its exit code, after its output; the figures printed are
each block's wall time. Usage (from the clone, with any Python 3.10+):

    python3 .ci/front_door.py               # into a temporary folder, removed after
    python3 .ci/front_door.py --keep DIR    # into DIR, kept (DIR must not exist)
"""

from __future__ import annotations

import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
#: A fenced block (its language and text) with the marker comment on the line above it.
_MARKED = re.compile(r"^<!-- front door[^\n]*-->\n```(\w+)\n(.*?)^```", re.S | re.M)


def blocks(readme: str) -> list[tuple[str, str]]:
    """The README's front-door blocks, ``(language, text)``, in order."""
    return [(language, text) for language, text in _MARKED.findall(readme)]


def copy_clone(to: Path) -> None:
    """The clone's files (tracked, and untracked but not ignored) copied to ``to``, without .git or .venv."""
    listed = subprocess.run(["git", "ls-files", "-z", "--cached", "--others", "--exclude-standard"], cwd=ROOT,
                            capture_output=True, check=True).stdout.decode().split("\0")
    for name in filter(None, listed):
        source = ROOT / name
        if source.is_file():
            (to / name).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(source, to / name)


def run(where: Path) -> int:
    """Run the front-door blocks in ``where`` (a copy of the clone); 0, or the first failing block's exit code."""
    found = blocks((where / "README.md").read_text())
    if not found:
        print("front door: the README marks no block", file=sys.stderr)
        return 1
    env = {k: v for k, v in os.environ.items() if k not in ("VIRTUAL_ENV", "PYTHONPATH", "PYTHONHOME")}
    for i, (language, text) in enumerate(found, 1):
        if language == "bash":
            argv = ["bash", "-euo", "pipefail", "-c", text]
        elif language == "python":
            argv = [str(where / ".venv" / "bin" / "python"), "-c", text]
        else:
            print(f"front door: block {i} is {language}, not bash or python", file=sys.stderr)
            return 1
        first = text.strip().splitlines()[0]
        print(f"front door {i}/{len(found)} ({language}): {first}", flush=True)
        began = time.monotonic()
        code = subprocess.run(argv, cwd=where, env=env).returncode
        print(f"front door {i}/{len(found)}: exit {code} after {time.monotonic() - began:.1f} s", flush=True)
        if code != 0:
            return code
    return 0


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--keep", metavar="DIR", type=Path, help="run in DIR (new) and keep it")
    args = parser.parse_args(argv)
    if args.keep is not None:
        if args.keep.exists():
            parser.error(f"--keep {args.keep} exists; give a new folder")
        args.keep.mkdir(parents=True)
        copy_clone(args.keep)
        return run(args.keep)
    with tempfile.TemporaryDirectory(prefix="somarm-front-door-") as folder:
        copy_clone(Path(folder))
        return run(Path(folder))


if __name__ == "__main__":
    sys.exit(main())
