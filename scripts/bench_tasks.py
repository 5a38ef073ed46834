"""Benchmark the tasks: evaluations per second through MuJoCo (batched) and the closed forms.

Same as ``somarm bench tasks``; all the logic lives in ``somarm.benchmarks.tasks``.

Usage:
  python scripts/bench_tasks.py                 # full batches, best of 3
  python scripts/bench_tasks.py --quick         # a smoke run
  python scripts/bench_tasks.py --only throw    # some tasks only
"""

from __future__ import annotations

import os
import sys

os.environ.setdefault("MUJOCO_GL", "disable")

from somarm.benchmarks.tasks import main  # noqa: E402  (after MUJOCO_GL is set)

if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
