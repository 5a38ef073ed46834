"""``run_sweep``: check the sweep, run what is missing on an engine, write the tables."""

from __future__ import annotations

from pathlib import Path
from typing import Literal

from somarm.io import atomic_write_json
from somarm.sweep import store
from somarm.sweep.spec import SweepSpec, config_key
from somarm.sweep.work import plan_chunks, validate_points

__all__ = ["ENGINES", "SweepOutcome", "run_sweep"]

ENGINES = ("local", "ray")


class SweepOutcome:
    """What ``run_sweep`` returns: the table of every row on disk and whether the sweep stopped early."""

    def __init__(self, table: store.Table, summary: str, interrupted: bool, n_run: int):
        self.table, self.summary, self.interrupted, self.n_run = table, summary, interrupted, n_run


def run_sweep(
    spec: SweepSpec,
    out: str | Path,
    *,
    engine: Literal["local", "ray"] = "local",
    workers: int | None = None,
    address: str | None = None,
    max_group_bytes: float = 2e9,
    progress: bool = True,
    figure: bool = True,
) -> SweepOutcome:
    """Run every point of ``spec`` at every seed that ``out`` does not hold yet, then write the tables.

    Args:
      spec: the sweep (checked here).
      out: the sweep folder: ``sweep.json``, ``points/``, ``results.csv``, ``best.json``, ``sweep.png``.
      engine: ``local`` (lockstep in this process, or ``workers`` processes) or ``ray`` (Ray Tune).
      workers: processes (local, default 1) or trials at once (ray, default: the cluster's CPUs).
      address: the Ray cluster to join (ray engine only).
      max_group_bytes: estimated learner memory of one lockstep group; bigger groups are cut.
      progress: progress bars (local) or Tune's status table (ray).
      figure: draw ``sweep.png``.

    Returns:
      A ``SweepOutcome``; ``interrupted`` when Ctrl-C or SIGTERM stopped it (the tables then hold
      the rows that finished, and rerunning the same sweep finishes the rest).

    Raises:
      ValueError: a bad spec, point, engine or folder (one line), before anything runs.
    """
    if engine not in ENGINES:
        raise ValueError(f"unknown engine {engine!r}; allowed: {', '.join(ENGINES)}")
    if address and engine != "ray":
        raise ValueError("--address joins a Ray cluster: it needs --engine ray")
    spec = spec.check()
    points = spec.points()
    validate_points(spec, points)
    out = Path(out)
    try:
        (out / "points").mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise ValueError(f"cannot create sweep folder {out}: {exc.strerror or exc}") from None
    atomic_write_json(out / "sweep.json", {**spec.to_dict(), "points": points})
    items = [(i, seed, spec.config(p, seed)) for i, p in enumerate(points) for seed in spec.seeds()]
    done = store.load_rows(out)
    # A failed row is retried on a rerun (the failure may have been the machine's, not the point's).
    todo = [item for item in items if done.get(config_key(item[2]), {"error": "missing"}).get("error")]
    chunks = plan_chunks(todo, max_bytes=max_group_bytes)

    def save(row: dict) -> None:
        store.save_row(out, row)

    interrupted = False
    if todo and engine == "local":
        from somarm.sweep.local import run_local

        interrupted = run_local(chunks, save, workers=workers or 1, progress=progress)
    elif todo:
        from somarm.sweep.ray_engine import experiment_name, run_ray

        name = experiment_name([config_key(c) for _, _, c in items])
        interrupted = run_ray(chunks, save, out=out, name=name, address=address, workers=workers,
                              progress=progress)
    table = store.Table(spec, points, store.load_rows(out))
    summary = store.write_outputs(out, table, figure=figure)
    return SweepOutcome(table, summary, interrupted, len(todo))
