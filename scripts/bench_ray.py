"""What Ray costs and what it buys on one machine: ``reproduce`` with ``--jobs 2`` against ``--engine ray``.

Two measurements, in one run, on this machine (a local Ray, one CPU per core):

1. ``part``: the wall time of ``somarm reproduce --only benchmarks_pendulum --seeds N`` with ``--jobs 2``
   (one part: its comparison's learner-seed units one after another in one process) and with
   ``--engine ray`` (the units on the local Ray, as many at once as it has CPUs), each in a fresh
   process, Ray's start-up included; their ratio. ``--quick`` (the default here) runs the part at its
   reduced budgets; ``--full`` at the benchmark's own (hours of TD3 and SAC).
2. ``overhead``: Ray's cost per unit, the wall time of ``--units`` units that do nothing, run through
   ``somarm.cluster.run_units`` on an already started local Ray, divided by their count.

The machine's core count and load average are printed with the figures, since on a shared machine the
load is part of them.

Usage:
  python scripts/bench_ray.py                   # both, the part at --quick and 5 seeds
  python scripts/bench_ray.py --skip-part       # the overhead alone (about a minute)
  python scripts/bench_ray.py --seeds 2 --full
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time


def nothing(i: int) -> int:
    """A unit that does nothing (what Ray's round trip costs)."""
    return i


def time_part(engine_args: list[str], *, seeds: int, quick: bool) -> float:
    """Wall seconds of one ``somarm reproduce --only benchmarks_pendulum`` in a fresh process."""
    with tempfile.TemporaryDirectory(prefix="somarm-bench-ray-") as folder:
        argv = [sys.executable, "-m", "somarm.cli", "reproduce", "--only", "benchmarks_pendulum", "--seeds",
                str(seeds), "--out", os.path.join(folder, "report"), "--no-progress", *engine_args]
        if quick:
            argv.append("--quick")
        start = time.perf_counter()
        subprocess.run(argv, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        return time.perf_counter() - start


def overhead(units: int) -> tuple[float, float]:
    """Seconds per unit through ``run_units`` on a started local Ray, and Ray's start-up seconds."""
    import ray

    from somarm import cluster
    from somarm.sweep.ray_engine import start_local

    began = time.perf_counter()
    start_local(os.cpu_count() or 1)
    ray.get(ray.remote(nothing).remote(0))  # a worker is up
    started = time.perf_counter() - began
    try:
        work = [cluster.Unit(f"unit {i}", nothing, (i,)) for i in range(units)]
        began = time.perf_counter()
        failed = cluster.run_units(work, on_done=lambda unit, result: None, progress=False)
        per_unit = (time.perf_counter() - began) / units
        assert not failed, failed
    finally:
        ray.shutdown()
    return per_unit, started


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=5, help="seeds of the part (5)")
    parser.add_argument("--full", action="store_true", help="the part at the benchmark's own budgets (hours)")
    parser.add_argument("--units", type=int, default=50, help="units that do nothing, for the overhead (50)")
    parser.add_argument("--skip-part", action="store_true", help="the overhead alone")
    args = parser.parse_args(argv)
    print(f"{os.cpu_count()} cores; 1-minute load average {os.getloadavg()[0]:.2f} at the start", flush=True)
    if not args.skip_part:
        quick = not args.full
        jobs = time_part(["--jobs", "2"], seeds=args.seeds, quick=quick)
        on_ray = time_part(["--engine", "ray"], seeds=args.seeds, quick=quick)
        mode = "--quick" if quick else "full budgets"
        print(f"reproduce --only benchmarks_pendulum --seeds {args.seeds} ({mode}): --jobs 2 {jobs:.1f} s, "
              f"--engine ray {on_ray:.1f} s (Ray's start-up included); ray / jobs = {on_ray / jobs:.2f}; "
              f"load average {os.getloadavg()[0]:.2f}", flush=True)
    per_unit, started = overhead(args.units)
    print(f"Ray's overhead: {1000 * per_unit:.1f} ms per unit ({args.units} units that do nothing, through "
          f"somarm.cluster.run_units), {started:.1f} s to start a local Ray; load average "
          f"{os.getloadavg()[0]:.2f}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
