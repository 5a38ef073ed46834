"""``somarm sweep``: its own options (the run settings come from ``RunConfig``) and the command."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from somarm.validation import number, whole_number

__all__ = ["add_options", "main"]


def add_options(parser: argparse.ArgumentParser) -> None:
    """The sweep's own options; ``somarm.cli`` adds the run settings (``run.add_options``) beside them."""
    parser.add_argument("--grid", action="append", default=[], metavar="KEY=V1,V2,...",
                        help="grid axis over a --set key or task.KEY (repeat for a product)")
    parser.add_argument("--random", action="append", default=[], metavar="KEY=LOW:HIGH[:log]",
                        help="random axis, drawn --samples times (whole numbers if LOW and HIGH are)")
    parser.add_argument("--samples", type=whole_number, default=0, metavar="N", help="random draws (each with every grid point)")
    parser.add_argument("--sample-seed", type=whole_number, default=0, metavar="S", help="seed of the random draws (default 0)")
    parser.add_argument("--seeds", type=whole_number, default=1, metavar="K",
                        help="seeds --seed .. --seed+K-1, each an independent set of trials (default 1)")
    parser.add_argument("--out", metavar="DIR", help="sweep folder (default sweeps/TASK); a rerun finishes what is missing")
    parser.add_argument("--force", action="store_true",
                        help="replace what --out holds when it is not this sweep (the same sweep goes on where it stopped)")
    parser.add_argument("--engine", default="local", metavar="NAME", help="local (default: lockstep here) or ray (Ray Tune)")
    parser.add_argument("--address", metavar="ADDR", help="Ray cluster to join (--engine ray; default: start a local one)")
    parser.add_argument("--workers", type=whole_number, metavar="W", help="processes (local, default 1) or trials at once (ray)")
    parser.add_argument("--max-group-mb", type=number, default=2000.0, metavar="MB",
                        help="learner memory of one lockstep group before it is cut (default 2000)")
    parser.add_argument("--no-figures", action="store_true", help="skip sweep.png")
    parser.add_argument("--no-progress", action="store_true", help="no progress output")


def main(args: argparse.Namespace) -> int:
    """Run ``somarm sweep`` from parsed options; 0 when done, 130 when stopped (partial tables written).

    Raises:
      ValueError: a bad option, spec or point (one line), before anything runs.
    """
    from somarm import run
    from somarm.run.names import folder_part
    from somarm.run.stopping import sigterm_as_interrupt
    from somarm.sweep import SweepSpec, parse_grid, parse_random, run_sweep
    from somarm.validation import check_int, check_number

    if args.workers is not None:
        check_int("--workers", args.workers)
    check_number("--max-group-mb", args.max_group_mb, minimum=0.0, strict_minimum=True)
    axes = tuple(parse_grid(g) for g in args.grid) + tuple(parse_random(r) for r in args.random)
    spec = SweepSpec.around(run.from_options(args), axes, n_seeds=args.seeds, n_samples=args.samples,
                            sample_seed=args.sample_seed)
    out = args.out or f"sweeps/{folder_part(spec.task)}"
    sigterm_as_interrupt()
    outcome = run_sweep(spec, out, engine=args.engine, workers=args.workers, address=args.address,
                        max_group_bytes=args.max_group_mb * 1e6, progress=not args.no_progress,
                        figure=not args.no_figures, force=args.force)
    print(outcome.summary)
    if outcome.interrupted:
        print(f"interrupted: partial results in {out}; rerun the same command to finish", file=sys.stderr)
        return 130
    finished = [row for row in outcome.table.rows if not row.get("error")]
    if not finished:
        first = outcome.table.rows[0].get("error", "") if outcome.table.rows else ""
        raise ValueError(f"no point of the sweep finished (the first failed with: {first}); "
                         f"results.csv in {out} lists each point's error")
    written = [name for name in ("results.csv", "best.json", "sweep.png") if (Path(out) / name).is_file()]
    print(f"results in {out}: {', '.join(written)}")
    return 0
