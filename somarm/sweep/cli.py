"""``somarm sweep``: search learner settings and task parameters over seeds."""

from __future__ import annotations

import argparse
import sys

__all__ = ["main", "parser"]


class _Parser(argparse.ArgumentParser):
    def error(self, message: str):  # noqa: D401 - argparse's signature
        raise ValueError(message)


def parser() -> argparse.ArgumentParser:
    p = _Parser(prog="somarm sweep", description="Run every point of a parameter grid (or random draws) "
                "over seeds; write results.csv, best.json and sweep.png.")
    p.add_argument("task", help="task name (see `somarm tasks`)")
    p.add_argument("--learner", default="somq", help="somq (default) or motoric")
    p.add_argument("--preset", help="parameter table (see `somarm presets`); default: the task's")
    p.add_argument("--grid", action="append", default=[], metavar="KEY=V1,V2,...",
                   help="grid axis over a --set key or task.KEY (repeat for a product)")
    p.add_argument("--random", action="append", default=[], metavar="KEY=LOW:HIGH[:log]",
                   help="random axis, drawn --samples times (whole numbers if LOW and HIGH are)")
    p.add_argument("--samples", type=int, default=0, help="random draws (each with every grid point)")
    p.add_argument("--sample-seed", type=int, default=0, help="seed of the random draws (default 0)")
    p.add_argument("--set", action="append", metavar="KEY=VALUE", help="a learner setting fixed for all points")
    p.add_argument("--task-set", action="append", metavar="KEY=VALUE", help="a task parameter fixed for all")
    p.add_argument("--trials", type=int, default=5, help="trials per point and seed (default 5)")
    p.add_argument("--steps", type=int, help="training steps (default: the task's)")
    p.add_argument("--seed", type=int, default=0, help="the first seed (default 0)")
    p.add_argument("--seeds", type=int, default=1, help="seeds S..S+K-1, one row each (default 1)")
    p.add_argument("--backend", default="mujoco", help="mujoco (default) or analytic")
    p.add_argument("--block", type=int, default=100, help="steps per learning-curve block (default 100)")
    p.add_argument("--out", help="sweep folder (default sweeps/TASK); a rerun finishes what is missing")
    p.add_argument("--engine", default="local", help="local (default: lockstep here) or ray (Ray Tune)")
    p.add_argument("--address", help="Ray cluster to join (--engine ray; default: start a local one)")
    p.add_argument("--workers", type=int, help="processes (local, default 1) or trials at once (ray)")
    p.add_argument("--max-group-mb", type=float, default=2000.0,
                   help="learner memory of one lockstep group before it is cut (default 2000)")
    p.add_argument("--no-figures", action="store_true", help="skip sweep.png")
    p.add_argument("--no-progress", action="store_true", help="no progress output")
    return p


def main(argv: list[str] | None = None) -> int:
    """Run ``somarm sweep``; exit 0 when done, 130 when stopped (partial tables written)."""
    from somarm.sweep import SweepSpec, parse_grid, parse_random, run_sweep
    from somarm.training import parse_assignments
    from somarm.validation import check_int

    args = parser().parse_args(argv)
    if args.workers is not None:
        check_int("--workers", args.workers)
    spec = SweepSpec(
        task=args.task, learner=args.learner, preset=args.preset,
        axes=tuple(parse_grid(g) for g in args.grid) + tuple(parse_random(r) for r in args.random),
        n_samples=args.samples, sample_seed=args.sample_seed,
        overrides=parse_assignments(args.set, "--set"),
        task_params=parse_assignments(args.task_set, "--task-set"),
        n_trials=args.trials, n_steps=args.steps, seed=args.seed, n_seeds=args.seeds, backend=args.backend, block=args.block,
    )
    out = args.out or f"sweeps/{args.task}"
    outcome = run_sweep(spec, out, engine=args.engine, workers=args.workers, address=args.address,
                        max_group_bytes=args.max_group_mb * 1e6, progress=not args.no_progress,
                        figure=not args.no_figures)
    print(outcome.summary)
    if outcome.interrupted:
        print(f"interrupted: partial results in {out}; rerun the same command to finish", file=sys.stderr)
        return 130
    print(f"results in {out}: results.csv, best.json" + ("" if args.no_figures else ", sweep.png"))
    return 0
