"""The ``somarm`` command line: tasks, train, evaluate, reproduce, bench, view."""

from __future__ import annotations

import argparse
import importlib
import os
import sys

__all__ = ["main"]

_BENCHMARKS = ("learner", "tasks")


def _bench(argv: list[str]) -> int:
    if not argv or argv[0] not in _BENCHMARKS:
        print(f"somarm bench: name one of: {', '.join(_BENCHMARKS)}", file=sys.stderr)
        return 2
    module = importlib.import_module(f"somarm.benchmarks.{argv[0]}")
    return int(module.main(argv[1:]) or 0)


def _view(argv: list[str]) -> int:
    module = importlib.import_module("somarm.viewer.cli")
    return int(module.main(argv) or 0)


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``somarm`` console script."""
    os.environ.setdefault("MUJOCO_GL", "disable")  # no rendering: the viewer is meshcat
    argv = list(sys.argv[1:] if argv is None else argv)
    parser = argparse.ArgumentParser(prog="somarm", description=__doc__)
    parser.add_argument("command", choices=["bench", "view"], help="what to do")
    if argv and argv[0] == "bench":
        return _bench(argv[1:])
    if argv and argv[0] == "view":
        return _view(argv[1:])
    parser.parse_args(argv)
    return 0


if __name__ == "__main__":
    sys.exit(main())
