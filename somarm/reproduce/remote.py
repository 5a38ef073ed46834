"""``somarm reproduce --engine ray``: the experiments as units on a Ray cluster (``somarm.cluster``).

An experiment of the paper (or beyond it) is one unit of one CPU: a worker runs it into a temporary
folder of its own, with its physics on one thread, and sends back its report section and the bytes
of every file it wrote there (its figures), since a worker on another machine has no disk in common
with this one. This process writes them under the output folder and rewrites the report after each,
as under ``--jobs``; the numbers and figures equal a run here, for every experiment draws from its
own seeds. The parts made of comparisons (``peers`` and Gymnasium's benchmarks) run here after the
others, their learner-seed units on the cluster (``somarm.peers.compare``'s engine), each seed record
written here as it comes back.
"""

from __future__ import annotations

import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

from somarm.io import atomic_write_bytes
from somarm.reproduce.common import Context, run_experiment
from somarm.reproduce.report import Section

__all__ = ["run", "run_remote_experiment"]


def run_remote_experiment(experiment: Callable[[Context], Section], quick: bool, seeds: tuple[int, ...],
                          backend: str) -> tuple[Section, dict[str, bytes]]:
    """Run one experiment in this (worker) process into a folder of its own: its section, with its
    figures named relative to that folder, and every file it wrote, by relative path."""
    from somarm import tasks

    tasks.set_threads(1)  # one CPU per unit, as declared
    began = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="somarm-unit-") as folder:
        out = Path(folder)
        (out / "figures").mkdir()
        section = run_experiment(experiment, out, quick=quick, seeds=seeds, progress=False, backend=backend)
        section.wall_time_s = time.perf_counter() - began
        files = {str(p.relative_to(out)): p.read_bytes() for p in sorted(out.rglob("*")) if p.is_file()}
        section.figures = [Path(f).absolute().relative_to(out.absolute()) for f in section.figures]
    return section, files


def run(experiments: dict[str, Callable[[Context], Section]], out: Path, *, quick: bool, seeds: tuple[int, ...],
        backend: str, address: str | None, finished: Callable[[str, Section], None], progress: bool = True) -> int:
    """Run ``experiments`` as units on the cluster at ``address`` (None: a local Ray); ``finished(name,
    section)`` as each comes back, its files written under ``out`` first.

    Returns:
      0 when every experiment ran, 130 when interrupted (the finished ones were reported).

    Raises:
      ValueError: an experiment failed on the cluster (one line; the others were reported), Ray is
        missing or the cluster cannot be joined.
    """
    from somarm import cluster
    from somarm.reproduce.parallel import expected_durations

    units = [cluster.Unit(name, run_remote_experiment, (experiment, quick, seeds, backend), kind=name)
             for name, experiment in experiments.items()]

    def keep(unit: cluster.Unit, result: tuple[Section, dict[str, bytes]]) -> None:
        section, files = result
        for relative, data in files.items():
            (out / relative).parent.mkdir(parents=True, exist_ok=True)
            atomic_write_bytes(out / relative, data)
        section.figures = [out / f for f in section.figures]
        finished(unit.name, section)

    try:
        failed = cluster.run_units(units, on_done=keep, address=address, progress=progress,
                                   expected=expected_durations(quick, len(seeds)))
    except KeyboardInterrupt:
        print("\ninterrupted; the report holds the experiments that finished", file=sys.stderr, flush=True)
        return 130
    if failed:
        unit, why = failed[0]
        raise ValueError(f"{why}; {unit.name} failed on the cluster ({len(failed)} of {len(units)} experiment(s))")
    return 0
