"""The Ray engine: each Ray Tune trial trains one chunk of points in lockstep.

Needs the ``sweep`` extra (``pip install -e ".[sweep]"``); Ray is imported here only. Tune keeps
its state in ``DIR/ray/NAME`` (its ``storage_path``), so rerunning the same sweep restores the
experiment (``Tuner.restore(resume_unfinished=True, resume_errored=True)``) and runs only the
trials that did not finish. ``reuse_actors=True`` keeps one worker process per slot: a new process
per trial costs far more than the points it trains.
"""

from __future__ import annotations

import hashlib
import json
import os
from pathlib import Path

import somarm
from somarm.sweep.work import Chunk, failed_row, run_chunk

__all__ = ["run_ray", "experiment_name", "start_local"]


def _trainable(config: dict) -> None:
    """One Tune trial: a chunk in lockstep. Reports its rows, then fails if a point failed
    (so a restore with ``resume_errored`` runs it again)."""
    from ray import tune

    rows, _ = run_chunk(Chunk.from_dict(config["chunk"]), progress=False)  # never stopped by a signal here
    tune.report({"rows": json.dumps(rows), "n_rows": len(rows)})
    failed = [row["error"] for row in rows if row.get("error")]
    if failed:
        raise RuntimeError(f"{len(failed)} point(s) failed, the first with {failed[0]}")


def _trial_name(trial) -> str:
    """A short trial name (Tune's default spells out the whole chunk)."""
    first = trial.config["chunk"]["items"][0]
    return f"chunk_{trial.trial_id}_seed{first[1]}_{len(trial.config['chunk']['items'])}points"


def experiment_name(keys: list[str]) -> str:
    """The Tune experiment of a sweep: named by the run configurations it covers."""
    return "tune-" + hashlib.sha256(" ".join(sorted(keys)).encode()).hexdigest()[:12]


def _start(address: str | None, workers: int | None) -> bool:
    """Join the cluster at ``address``, or start a local one; True if this call started Ray."""
    import ray

    if ray.is_initialized():
        return False
    if address:
        ray.init(address=address, log_to_driver=False)
    else:
        start_local(workers or os.cpu_count() or 1)
    return True


def start_local(workers: int, **init_kwargs) -> None:
    """Start a local Ray cluster of ``workers`` CPUs whose workers import this very somarm.

    Args:
      workers: CPUs the cluster offers (trials at once).
      **init_kwargs: passed on to ``ray.init`` (e.g. ``_temp_dir``).
    """
    import ray

    # Tune runs each trial in its own folder, so a relative PYTHONPATH (or none, when somarm is used
    # from a checkout) would not find somarm there: give the workers absolute paths.
    package_root = str(Path(somarm.__file__).resolve().parents[1])
    paths = [package_root] + [os.path.abspath(p) for p in os.environ.get("PYTHONPATH", "").split(os.pathsep) if p]
    ray.init(num_cpus=workers, include_dashboard=False, log_to_driver=False,
             runtime_env={"env_vars": {"PYTHONPATH": os.pathsep.join(dict.fromkeys(paths))}}, **init_kwargs)


def run_ray(
    chunks: list[Chunk], save, *, out: Path, name: str, address: str | None = None,
    workers: int | None = None, progress: bool = True,
) -> bool:
    """Run the chunks as Ray Tune trials; each row goes to ``save`` when Tune is done.

    Args:
      chunks: the work still to do (``plan_chunks``); used when no experiment ``name`` exists yet.
      save: called with each finished or failed row.
      out: the sweep folder; Tune's state goes to ``out/ray/name``.
      name: the experiment (``experiment_name``): an existing one is restored instead.
      address: a Ray cluster to join (``ray start --head`` prints it); None starts a local one.
      workers: trials at once (None: as many as the cluster's CPUs allow).
      progress: Tune's status table on stdout.

    Returns:
      True when the sweep stopped before every trial finished (Ctrl-C); a rerun goes on from there.

    Raises:
      ValueError: Ray is not installed (one line saying how to install it).
    """
    try:
        from ray import tune
    except ImportError:
        from somarm.extras import missing

        raise missing("sweep", "the ray engine needs Ray Tune") from None
    started = _start(address, workers)
    try:
        storage = (out / "ray").resolve()
        path = storage / name
        trainable = tune.with_resources(_trainable, {"cpu": 1})
        if tune.Tuner.can_restore(str(path)):
            tuner = tune.Tuner.restore(str(path), trainable, resume_unfinished=True, resume_errored=True)
        else:
            tuner = tune.Tuner(
                trainable,
                param_space={"chunk": tune.grid_search([chunk.to_dict() for chunk in chunks])},
                tune_config=tune.TuneConfig(
                    reuse_actors=True, max_concurrent_trials=workers,
                    trial_name_creator=_trial_name, trial_dirname_creator=_trial_name,
                ),
                run_config=tune.RunConfig(
                    storage_path=str(storage),
                    name=name,
                    failure_config=tune.FailureConfig(max_failures=0, fail_fast=False),
                    verbose=1 if progress else 0,
                ),
            )
        results = tuner.fit()
        interrupted = False
        for result in results:
            chunk = Chunk.from_dict(result.config["chunk"])
            rows = json.loads((result.metrics or {}).get("rows", "[]"))
            for row in rows:
                save(row)
            if len(rows) == len(chunk.items):
                continue
            if result.error is None or isinstance(result.error, KeyboardInterrupt):
                interrupted = True  # never ran, or stopped by Ctrl-C: the rerun restores it
                continue
            done = {row["key"] for row in rows}
            for index, seed, config in chunk.items:
                row = failed_row(index, seed, config, result.error)
                if row["key"] not in done:
                    save(row)
        return interrupted
    finally:
        if started:
            import ray

            ray.shutdown()
