"""``somarm reproduce``: run the experiments, time them, and write REPORT.md atomically."""

from __future__ import annotations

import json
import os
import platform
import sys
import time
from collections.abc import Callable
from pathlib import Path

from somarm import __version__
from somarm.io import atomic_write_json, atomic_write_text, make_folder
from somarm.peers.compare import peers_missing
from somarm.reproduce import (
    against_peers,
    benchmarks,
    beyond,
    delayed,
    dmc,
    driven,
    four_goals,
    more_inputs,
    neighbourhood_q,
    reach2,
    reach20,
    throw,
    throw_maps,
)
from somarm.reproduce.common import Context, run_experiment
from somarm.reproduce.report import BENCHMARKS_TITLE, SUITE_TITLE, TITLE, Section, claim_record, render
from somarm.reproduce.sizes import check_seeds
from somarm.tasks.record import OWN_BACKENDS
from somarm.validation import check_int

__all__ = ["EXPERIMENTS", "OPTIONAL", "check_names", "check_request", "default_jobs", "reproduce", "load_claims"]

#: Every experiment of the paper, in the paper's order, then what goes beyond it.
EXPERIMENTS: dict[str, Callable[[Context], Section]] = {
    "reach2": reach2.reach2,
    "reach20": reach20.reach20,
    "four_goals": four_goals.four_goals,
    "throw": throw.throw,
    "throw_maps": throw_maps.throw_maps,
    "neighbourhood_q": neighbourhood_q.neighbourhood_q,
    "more_inputs": more_inputs.more_inputs,
    "driven_arm": driven.driven_arm,
    # Not the paper's: the continuous response its section 6 suggests, apart from the paper's claims.
    "beyond": beyond.beyond,
}

#: Parts run only when named with ``--only`` (they take far longer than the paper's experiments).
OPTIONAL: dict[str, Callable[[Context], Section]] = {
    "delayed_reward": delayed.delayed_reward, "peers": against_peers.peers, "benchmarks": benchmarks.benchmarks,
    **benchmarks.PARTS, **dmc.PARTS,
}
#: The parts that run Gymnasium's environments (the whole benchmarks part and each environment alone).
GYMNASIUM_PARTS = frozenset({"benchmarks", *benchmarks.PARTS, *dmc.PARTS})


def check_names(only: list[str] | None) -> list[str]:
    """The experiments to run, in the paper's order; ValueError listing the names for an unknown one."""
    names = list(only or EXPERIMENTS)
    unknown = [n for n in names if n not in EXPERIMENTS and n not in OPTIONAL]
    if unknown:
        raise ValueError(f"unknown experiment(s) {', '.join(unknown)}; allowed: {', '.join([*EXPERIMENTS, *OPTIONAL])}")
    if ({"peers"} | GYMNASIUM_PARTS) & set(names) and (reason := peers_missing()):
        raise ValueError(reason)
    return names


def default_jobs() -> int:
    """``--jobs`` when none is given: the cores this process may run on (a run's numbers do not depend on it)."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # pragma: no cover - platforms without affinity (macOS, Windows)
        return max(1, os.cpu_count() or 1)


def check_request(only: list[str] | None, *, quick: bool, seed: int, seeds: int, jobs: int,
                  backend: str) -> list[str]:
    """The experiments to run, after every check that needs nothing written: the names, the counts,
    the backend and the memory of the seeds (the command line calls it before it claims ``--out``).

    Raises:
      ValueError: one line naming what is wrong and what is allowed.
    """
    names = check_names(only)
    check_int("--seeds", seeds)
    check_int("--jobs", jobs)
    if backend not in OWN_BACKENDS:
        raise ValueError(f"unknown backend {backend!r}; allowed: {', '.join(OWN_BACKENDS)}")
    check_seeds({n: {**EXPERIMENTS, **OPTIONAL}[n] for n in names}, quick=quick, seed=seed, seeds=seeds,
                backend=backend)
    return names


def reproduce(
    out: Path, *, quick: bool = False, only: list[str] | None = None, seed: int = 0, progress: bool = True,
    seeds: int = 1, backend: str = "mujoco", jobs: int = 1, final_out: Path | None = None,
    engine: str = "local", address: str | None = None,
) -> int:
    """Run the chosen experiments and write ``out/REPORT.md``, ``out/claims.json`` and the figures.

    Args:
      seeds: run every experiment at the seeds ``seed .. seed + seeds - 1`` (independent trial
        sets, trained in lockstep); each claim's verdict then reads "holds in k of N seeds".
      backend: where every reward is computed, "mujoco" (default) or "analytic" (closed forms).
      jobs: experiments run at once, each in its own process (``somarm.reproduce.parallel``); 1
        (default) runs them one after another in this process, with progress bars, as does a single
        experiment (the command line's default is ``default_jobs``, the number of cores).
      final_out: the folder the report ends up in when the caller moves it there from ``out`` (a
        forced run writes into a staging folder first); the path printed at the end. Default ``out``.
      engine: "local" (``jobs`` decides), or "ray": every experiment a unit on the Ray cluster at
        ``address`` (None: a local one), the comparisons' parts here with their learner-seed units
        there (``somarm.reproduce.remote``); the numbers equal a local run's.

    Returns:
      0 when every experiment ran (whatever the verdicts), 130 when interrupted (the report then
      holds the experiments that finished).

    Raises:
      ValueError: before anything is written: an unknown experiment or backend, seeds < 1 or more than fit in memory.
    """
    names = check_request(only, quick=quick, seed=seed, seeds=seeds, jobs=jobs, backend=backend)
    make_folder(out / "figures", within=out)  # a link planted there is refused, never written through
    all_seeds = tuple(range(seed, seed + seeds))
    settings = {"quick": quick, "seeds": list(all_seeds), "backend": backend}
    sections: list[Section] = []
    start = time.perf_counter()
    kept: list[tuple[int, Section]] = []  # (place in ``names``, section): workers finish in any order

    def finished(name: str, section: Section) -> None:
        """Keep a finished experiment (in the order asked) and rewrite the report with it."""
        kept.append((names.index(name), section))
        sections[:] = [part for _, part in sorted(kept, key=lambda pair: pair[0])]
        print(f"{name}: {section.wall_time_s:.1f} s", file=sys.stderr, flush=True)
        _write(out, sections, total=time.perf_counter() - start, complete=False, **settings)

    experiments = {name: {**EXPERIMENTS, **OPTIONAL}[name] for name in names}
    try:
        status = _run(experiments, out, quick=quick, seeds=all_seeds, progress=progress, backend=backend, jobs=jobs,
                      engine=engine, address=address, finished=finished)
    except ValueError as exc:  # an experiment could not write (a full disk): keep the report so far
        _keep_report(out, sections, total=time.perf_counter() - start, **settings)
        raise ValueError(f"{exc}, the report keeps the {len(sections)} experiment(s) that finished") from None
    total = time.perf_counter() - start
    _write(out, sections, total=total, complete=status == 0, **settings)
    _print_summary(sections, (final_out or out) / "REPORT.md", seeds=seeds, total=total)
    return status


def _print_summary(sections: list[Section], report: Path, *, seeds: int, total: float) -> None:
    """The last line: where the report is, how many claims hold, and the wall time."""
    held = sum(c.holds is True for s in sections for c in s.claims)
    claims = sum(len(s.claims) for s in sections)
    over = f" in every one of {seeds} seeds" if seeds > 1 else ""
    print(f"report: {report} ({held} of {claims} claims hold{over}; {total:.1f} s)")


def _run(experiments: dict[str, Callable[[Context], Section]], out: Path, *, quick: bool, seeds: tuple[int, ...],
         progress: bool, backend: str, jobs: int, engine: str, address: str | None,
         finished: Callable[[str, Section], None]) -> int:
    """The experiments on the cluster (``engine="ray"``), in worker processes (``jobs`` > 1 and more than
    one experiment), or one after another here; 0, or 130 when interrupted."""
    if engine == "ray":
        return _run_on_ray(experiments, out, quick=quick, seeds=seeds, progress=progress, backend=backend,
                           address=address, finished=finished)
    if min(jobs, len(experiments)) > 1:  # one experiment alone runs here, with its progress bars
        from somarm.reproduce import parallel

        return parallel.run(experiments, out, jobs=jobs, quick=quick, seeds=seeds, backend=backend,
                            finished=finished, progress=progress)
    return _run_in_turn(experiments, out, quick=quick, seeds=seeds, progress=progress, backend=backend,
                        finished=finished)


def _run_on_ray(experiments: dict[str, Callable[[Context], Section]], out: Path, *, quick: bool,
                seeds: tuple[int, ...], progress: bool, backend: str, address: str | None,
                finished: Callable[[str, Section], None]) -> int:
    """``--engine ray``: the experiments as units on the cluster, then the comparisons' parts here with
    their units there; 130 when interrupted."""
    from somarm import cluster
    from somarm.peers.compare import engine_of_parts
    from somarm.reproduce import remote

    comparisons = {n: e for n, e in experiments.items() if n in GYMNASIUM_PARTS or n == "peers"}
    units = {n: e for n, e in experiments.items() if n not in comparisons}
    started = cluster.join(address)  # one cluster for both kinds of part
    try:
        status = remote.run(units, out, quick=quick, seeds=seeds, backend=backend, address=address,
                            finished=finished, progress=progress) if units else 0
        if status or not comparisons:
            return status
        with engine_of_parts("ray", address):
            return _run_in_turn(comparisons, out, quick=quick, seeds=seeds, progress=progress, backend=backend,
                                finished=finished)
    finally:
        cluster.leave(started)


def _run_in_turn(experiments: dict[str, Callable[[Context], Section]], out: Path, *, quick: bool,
                 seeds: tuple[int, ...], progress: bool, backend: str,
                 finished: Callable[[str, Section], None]) -> int:
    """The experiments one after another in this process (with progress bars); 130 when interrupted.

    Raises:
      ValueError: an experiment's one-line error, naming the experiment that stopped.
    """
    for name, experiment in experiments.items():
        began = time.perf_counter()
        try:
            section = run_experiment(experiment, out, quick=quick, seeds=seeds, progress=progress, backend=backend)
        except KeyboardInterrupt:
            print(f"\ninterrupted during {name}; the report holds the experiments that finished", file=sys.stderr)
            return 130
        except ValueError as exc:
            raise ValueError(f"{exc}; {name} stopped") from None
        section.wall_time_s = time.perf_counter() - began
        finished(name, section)
    return 0


def _keep_report(out: Path, sections: list[Section], **kwargs) -> None:
    """Write the report of the finished experiments, if there is room for it (best effort)."""
    try:
        _write(out, sections, complete=False, **kwargs)
    except ValueError:
        pass  # the report of the previous experiment stays as it was


def _write(
    out: Path, sections: list[Section], *, quick: bool, seeds: list[int], backend: str, total: float,
    complete: bool,
) -> None:
    benchmarks_only = bool(sections) and all(s.name in GYMNASIUM_PARTS for s in sections)
    suite_only = benchmarks_only and all(s.name in dmc.PARTS for s in sections)
    header = _header(sections, quick=quick, seeds=seeds, backend=backend, total=total, complete=complete,
                     benchmarks_only=benchmarks_only, suite_only=suite_only)
    title = SUITE_TITLE if suite_only else BENCHMARKS_TITLE if benchmarks_only else TITLE
    atomic_write_text(out / "REPORT.md", render(sections, header=header, out_dir=out, seeds=seeds, title=title))
    atomic_write_json(
        out / "claims.json",
        {
            "quick": quick,
            "seed": seeds[0],
            "seeds": seeds,
            "backend": backend,
            "complete": complete,
            "wall_time_s": round(total, 2),
            "experiments": {
                s.name: {"wall_time_s": round(s.wall_time_s, 2), "claims": [claim_record(c) for c in s.claims],
                         "counts": s.counts}
                for s in sections
            },
        },
    )


def _header(sections: list[Section], *, quick: bool, seeds: list[int], backend: str, total: float,
            complete: bool, benchmarks_only: bool, suite_only: bool = False) -> list[str]:
    """The report's opening lines: the mode, the seeds, where rewards come from, the wall time and
    which values are this project's choices (the benchmarks part alone runs Gymnasium's own
    environments, and its seeds may be read back from an earlier run)."""
    slowest = max(sections, key=lambda s: s.wall_time_s, default=None)
    if suite_only:
        where = "every return from the DeepMind Control Suite's own tasks (through Gymnasium's API)"
    elif benchmarks_only:
        where = "every return from Gymnasium's own environment"
    elif backend == "mujoco":
        where = "every reward evaluated in MuJoCo (the tasks' default backend)"
    else:
        where = ("every reward from the closed forms (backend `analytic`, a quick look; the default is MuJoCo; a "
                 "task without closed forms, reach2_obstacle, stays in MuJoCo)")
    seed_text = (f"seed {seeds[0]}" if len(seeds) == 1 else
                 f"{len(seeds)} seeds ({seeds[0]} to {seeds[-1]}: independent trial sets; figures from seed "
                 f"{seeds[0]}; each verdict says in how many seeds the claim holds)")
    timing = (f"Wall time of this run {total:.1f} s (learner seeds kept from an earlier run with `--resume` are "
              "read back, not trained again; each learner's own training seconds are in the table)"
              if benchmarks_only else f"Total wall time {total:.1f} s")
    choices = ("The presets, run lengths, the peers' budgets, the targets and the yardsticks are this project's "
               f"choices, stated in the part; the paper ran no {'suite task' if suite_only else 'Gymnasium environment'}."
               if benchmarks_only else
               "Arm lengths, the goal circle, the four goals, the reading of epsilon in Tables 1 and 2 (a fraction of "
               "the angle range), the Motoric Map's rules, run lengths and the levels and bounds used in the "
               "verdicts are this project's choices, stated in each part; the paper publishes none of them.")
    return [
        f"Mode: **{'quick (reduced trial counts: verdicts are indicative only)' if quick else 'full'}**; "
        f"{seed_text}; {where}; somarm {__version__}, "
        f"Python {platform.python_version()}, {platform.machine()}.",
        "",
        timing
        + (f"; slowest experiment `{slowest.name}` ({slowest.wall_time_s:.1f} s)." if slowest else ".")
        + ("" if complete else " **Incomplete: not every experiment has run.**"),
        "",
        choices,
    ]


def load_claims(out: Path) -> dict:
    """The machine-readable verdicts of a report folder (for tests and tools)."""
    return json.loads((out / "claims.json").read_text())
