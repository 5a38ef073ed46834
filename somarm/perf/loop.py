"""``somarm bench loop``: milliseconds per training step of a few lockstep groups of the reproduction.

Each group (``run.RunGroup``) is built, then trained for ``--steps`` steps without a progress bar;
the figure is the training's wall time per step (building excluded), the best of ``--repeats``
runs. It is the cost of the loop itself with its physics and learners: compare two checkouts by
running it in each, interleaved, on the same machine.
"""

from __future__ import annotations

import time

from somarm.helptext import PlainHelpFormatter
from somarm.run import RunConfig, RunGroup
from somarm.validation import OneLineParser, check_int, whole_number

__all__ = ["GROUPS", "step_ms", "main"]

#: Groups of the reproduction, by label: (task, preset, n_trials) of each config (each its own seed).
GROUPS: dict[str, list[tuple[str, str, int]]] = {
    "Fig 25: four throw tasks x 100 trials": [("throw", "table7", 100), ("throw_wind", "table7", 100),
                                              ("throw_friction", "table7", 100), ("throw_mass", "table7", 100)],
    "Figs 21-23: throw_distance, 3 x 3 trials": [("throw_distance", "table5", 3)] * 3,
    "Figs 7-10 at 5 seeds: reach2 x 20 trials": [("reach2", "table1", 20)] * 5,
}


def step_ms(label: str, *, n_steps: int) -> float:
    """Milliseconds per step of group ``label`` (``GROUPS``), building excluded."""
    configs = [RunConfig(task=task, preset=preset, n_trials=n, n_steps=n_steps, block=n_steps, seed=k)
               for k, (task, preset, n) in enumerate(GROUPS[label])]
    group = RunGroup(configs)
    start = time.perf_counter()
    group.train(progress=False)
    return (time.perf_counter() - start) / n_steps * 1e3


def main(argv: list[str] | None = None) -> int:
    """Print the table; returns 0 (a benchmark reports, it does not fail)."""
    parser = OneLineParser(prog="somarm bench loop", description=__doc__.splitlines()[0], formatter_class=PlainHelpFormatter)
    parser.add_argument("--quick", action="store_true", help="short runs, one repeat (a smoke run)")
    parser.add_argument("--repeats", type=whole_number, default=3, help="timed runs per figure, best kept (3)")
    parser.add_argument("--steps", type=whole_number, default=2000, help="steps per timed run (2000)")
    args = parser.parse_args(argv)
    repeats = 1 if args.quick else check_int("--repeats", args.repeats)
    n_steps = 100 if args.quick else check_int("--steps", args.steps)
    print(f"{'group':42s} {'ms/step':>9s}")
    for label in GROUPS:
        step_ms(label, n_steps=20)  # numba's compilation and MuJoCo's batch models outside the timing
        best = min(step_ms(label, n_steps=n_steps) for _ in range(repeats))
        print(f"{label:42s} {best:9.3f}", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
