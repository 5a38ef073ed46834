"""Benchmark the SOM-Q learner: microseconds per trial-step beside the line-by-line reference.

Same as ``somarm bench learner``; all the logic lives in ``somarm.benchmarks.learner``.

Usage:
  python scripts/bench_learner.py            # 2000 steps per timing, best of 3
  python scripts/bench_learner.py --quick    # a smoke run
  python scripts/bench_learner.py --t0 5000  # later in the annealing (narrower neighbourhoods)
"""

from __future__ import annotations

import os
import sys

os.environ.setdefault("MUJOCO_GL", "disable")

from somarm.benchmarks.learner import main  # noqa: E402  (after MUJOCO_GL is set)

if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
