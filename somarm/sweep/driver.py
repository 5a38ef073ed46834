"""``run_sweep``: check the sweep, run what is missing on an engine, write the tables."""

from __future__ import annotations

import importlib.util
import json
import os
from pathlib import Path
from typing import Literal

from somarm.io import atomic_write_json, make_folder, read_json
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
    force: bool = False,
) -> SweepOutcome:
    """Run every point of ``spec`` at every seed that ``out`` does not hold yet, then write the tables.

    The folder is claimed as a run folder is (``somarm.run.claim``): one sweep writes it at a time,
    the same sweep run again, or widened (more values or seeds), goes on where it stopped, and a
    folder holding anything else (another sweep, a run, a report) is refused unless ``force``, which
    replaces it once the new sweep's tables are written.

    Args:
      spec: the sweep (checked here).
      out: the sweep folder: ``sweep.json``, ``points/``, ``results.csv``, ``best.json``, ``sweep.png``.
      engine: ``local`` (lockstep in this process, or ``workers`` processes) or ``ray`` (Ray Tune).
      workers: processes (local, default 1) or trials at once (ray, default: the cluster's CPUs).
      address: the Ray cluster to join (ray engine only).
      max_group_bytes: estimated learner memory of one lockstep group; bigger groups are cut.
      progress: progress bars (local) or Tune's status table (ray).
      figure: draw ``sweep.png``.
      force: replace what ``out`` holds if it is not this sweep.

    Returns:
      A ``SweepOutcome``; ``interrupted`` when Ctrl-C or SIGTERM stopped it (the tables then hold
      the rows that finished, and rerunning the same sweep finishes the rest).

    Raises:
      ValueError: a bad spec, point, engine or folder (one line), before anything is written.
    """
    from somarm.run.claim import claim

    if engine not in ENGINES:
        raise ValueError(f"unknown engine {engine!r}; allowed: {', '.join(ENGINES)}")
    if address and engine != "ray":
        raise ValueError("--address joins a Ray cluster: it needs --engine ray")
    if engine == "ray" and importlib.util.find_spec("ray") is None:
        from somarm.extras import missing

        raise missing("sweep", "the ray engine needs Ray Tune")
    spec = spec.check()
    points = spec.points()
    validate_points(spec, points)
    folder = Path(out)
    described = {**spec.to_dict(), "points": points}
    same = _holds(folder, described)
    if not same and not force and os.path.isfile(folder / "sweep.json"):
        raise ValueError(f"--out {folder} holds another sweep (its settings or swept keys differ); give --force to "
                         "replace it, or another --out (the same sweep, or one with more values or seeds, goes on "
                         "where it stopped)")
    owner = claim(folder, force=force, resume=same, what="a sweep")
    try:
        outcome = _sweep_into(owner.path, spec, points, described, engine=engine, workers=workers,
                              address=address, max_group_bytes=max_group_bytes, progress=progress, figure=figure)
    except BaseException:
        owner.finish(False)
        raise
    else:
        owner.finish(not outcome.interrupted)  # an interrupted sweep does not replace another one
    finally:
        owner.release()
    return outcome


#: What may change between two runs of one sweep in one folder: the values swept and the seeds (a
#: widened sweep runs only its new rows; the folder's tables then show the sweep as run last).
_WIDENING = ("axes", "n_samples", "seed", "n_seeds", "sample_seed")


def _holds(folder: Path, described: dict) -> bool:
    """Whether ``folder`` holds this sweep or a narrower one of the same settings and swept keys (its
    ``sweep.json``), so that running it resumes in place."""
    try:
        held = read_json(folder / "sweep.json")
        ours = json.loads(json.dumps(described))
        same_keys = [a["key"] for a in held["axes"]] == [a["key"] for a in ours["axes"]]
        return same_keys and all(held.get(k) == v for k, v in ours.items() if k not in (*_WIDENING, "points"))
    except (OSError, UnicodeDecodeError, ValueError, RecursionError, KeyError, TypeError):
        return False


def _sweep_into(out: Path, spec: SweepSpec, points: list, described: dict, *, engine: str, workers: int | None,
                address: str | None, max_group_bytes: float, progress: bool, figure: bool) -> SweepOutcome:
    """Run what ``out`` lacks of the sweep and write its tables (``run_sweep``'s work, in a claimed folder)."""
    make_folder(out / "points", within=out)
    atomic_write_json(out / "sweep.json", described, within=out)
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
