"""How long the listing commands take to answer: ``somarm tasks``, ``somarm presets``, ``somarm --help``.

Each command runs in a fresh process ``--runs`` times (one after another, the commands interleaved so
that a change of load falls on all of them alike); the median wall time of each is printed with the
machine's core count and its load average before and after, since on a shared machine the load is
part of the figure. The target: each answers in under 1 s.

Usage:
  python scripts/bench_startup.py               # 5 runs of each
  python scripts/bench_startup.py --runs 9
  python scripts/bench_startup.py --imports     # also: which heavy packages each command imports
  python scripts/bench_startup.py --tree DIR    # the somarm package of another checkout (a before), same runs
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import time

COMMANDS = (("tasks",), ("presets",), ("--help",))
#: The commands run from the filesystem's root, so that no ``somarm`` folder of the working directory
#: comes before the one installed (or the one ``--tree`` names).
_HOME = os.path.abspath(os.sep)


def _somarm() -> list[str]:
    return [sys.executable, "-c", "import sys; from somarm.cli import main; sys.exit(main())"]


def _env(tree: str | None) -> dict[str, str]:
    return {**os.environ, "PYTHONPATH": tree} if tree else dict(os.environ)


def time_once(args: tuple[str, ...], tree: str | None = None) -> float:
    """Wall seconds of one ``somarm ARGS`` in a fresh interpreter (its output discarded); ``tree``: a
    folder holding another ``somarm`` package to time instead of the installed one."""
    start = time.perf_counter()
    subprocess.run([*_somarm(), *args], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=True,
                   env=_env(tree), cwd=_HOME)
    return time.perf_counter() - start


def heavy_imports(args: tuple[str, ...], tree: str | None = None) -> list[str]:
    """The heavy packages a command imports (numba, mujoco, dm_control, matplotlib, torch, gymnasium, ray)."""
    heavy = ("numba", "mujoco", "dm_control", "matplotlib", "torch", "gymnasium", "ray", "scipy")
    code = ("import sys, contextlib, io\nfrom somarm.cli import main\n"
            "with contextlib.redirect_stdout(io.StringIO()):\n"
            "    try:\n        main(sys.argv[1:])\n    except SystemExit:\n        pass\n"
            f"print(' '.join(sorted(m for m in {heavy!r} if m in sys.modules)))")
    out = subprocess.run([sys.executable, "-c", code, *args], capture_output=True, text=True, check=True,
                         env=_env(tree), cwd=_HOME)
    return out.stdout.split()


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=5, help="runs of each command (5)")
    parser.add_argument("--imports", action="store_true", help="also list the heavy packages each imports")
    parser.add_argument("--tree", metavar="DIR",
                        help="also time the somarm package in DIR (put first on PYTHONPATH), interleaved with this one")
    args = parser.parse_args(argv)
    if args.runs < 1:
        parser.error(f"--runs must be >= 1, got {args.runs}")
    trees = [None, args.tree] if args.tree else [None]
    load_before = os.getloadavg()[0]
    for tree in trees:
        for command in COMMANDS:  # a first run of each warms the file cache (and numba's, if imported)
            time_once(command, tree)
    times = {(tree, command): [] for tree in trees for command in COMMANDS}
    for _ in range(args.runs):
        for command in COMMANDS:
            for tree in trees:
                times[tree, command].append(time_once(command, tree))
    load_after = os.getloadavg()[0]
    print(f"{os.cpu_count()} cores; 1-minute load average {load_before:.2f} before, {load_after:.2f} after")
    for tree in trees:
        for command in COMMANDS:
            took = times[tree, command]
            line = (f"{'' if tree is None else tree + ': '}somarm {' '.join(command):8s} median "
                    f"{statistics.median(took):.2f} s (min {min(took):.2f}, max {max(took):.2f}, {args.runs} runs)")
            if args.imports:
                line += f"; imports: {' '.join(heavy_imports(command, tree)) or 'none of the heavy packages'}"
            print(line)
    return 0


if __name__ == "__main__":
    sys.exit(main())
