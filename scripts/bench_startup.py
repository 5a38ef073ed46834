"""How long the listing commands take to answer: ``somarm tasks``, ``somarm presets``, ``somarm --help``.

Each command runs in a fresh process ``--runs`` times (one after another, the commands interleaved so
that a change of load falls on all of them alike); the median wall time of each is printed with the
machine's core count and its load average before and after, since on a shared machine the load is
part of the figure. The target: each answers in under 1 s.

Usage:
  python scripts/bench_startup.py               # 5 runs of each
  python scripts/bench_startup.py --runs 9
  python scripts/bench_startup.py --imports     # also: which somarm-visible modules each command imports
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import time

COMMANDS = (("tasks",), ("presets",), ("--help",))


def _somarm() -> list[str]:
    return [sys.executable, "-c", "import sys; from somarm.cli import main; sys.exit(main())"]


def time_once(args: tuple[str, ...]) -> float:
    """Wall seconds of one ``somarm ARGS`` in a fresh interpreter (its output discarded)."""
    start = time.perf_counter()
    subprocess.run([*_somarm(), *args], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=True)
    return time.perf_counter() - start


def heavy_imports(args: tuple[str, ...]) -> list[str]:
    """The heavy packages a command imports (numba, mujoco, dm_control, matplotlib, torch, gymnasium, ray)."""
    heavy = ("numba", "mujoco", "dm_control", "matplotlib", "torch", "gymnasium", "ray", "scipy")
    code = ("import sys, contextlib, io\nfrom somarm.cli import main\n"
            "with contextlib.redirect_stdout(io.StringIO()):\n"
            "    try:\n        main(sys.argv[1:])\n    except SystemExit:\n        pass\n"
            f"print(' '.join(sorted(m for m in {heavy!r} if m in sys.modules)))")
    out = subprocess.run([sys.executable, "-c", code, *args], capture_output=True, text=True, check=True)
    return out.stdout.split()


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=5, help="runs of each command (5)")
    parser.add_argument("--imports", action="store_true", help="also list the heavy packages each imports")
    args = parser.parse_args(argv)
    if args.runs < 1:
        parser.error(f"--runs must be >= 1, got {args.runs}")
    load_before = os.getloadavg()[0]
    for command in COMMANDS:  # a first run of each warms the file cache (and numba's, if imported)
        time_once(command)
    times: dict[tuple[str, ...], list[float]] = {command: [] for command in COMMANDS}
    for _ in range(args.runs):
        for command in COMMANDS:
            times[command].append(time_once(command))
    load_after = os.getloadavg()[0]
    print(f"{os.cpu_count()} cores; 1-minute load average {load_before:.2f} before, {load_after:.2f} after")
    for command in COMMANDS:
        line = (f"somarm {' '.join(command):8s} median {statistics.median(times[command]):.2f} s "
                f"(min {min(times[command]):.2f}, max {max(times[command]):.2f}, {args.runs} runs)")
        if args.imports:
            line += f"; imports: {' '.join(heavy_imports(command)) or 'none of the heavy packages'}"
        print(line)
    return 0


if __name__ == "__main__":
    sys.exit(main())
