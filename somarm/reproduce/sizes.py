"""Before a reproduction writes anything: whether each experiment's training fits in memory at every seed.

An experiment trains its lockstep groups (its ``groups``) once for all the seeds of the run
(``common.run_group``), and keeps every group's results until its last seed has been measured;
so at ``--seeds N`` it holds N times the runs of one seed. ``check_seeds`` refuses a run that
cannot fit, with the estimate the groups themselves check when built (``run.memory_needs``), before
the report's folder is claimed: ``RunGroup``'s own check comes only once the folder is claimed.
"""

from __future__ import annotations

import sys
from collections.abc import Callable
from pathlib import Path

from somarm.reproduce.common import Context, at_seeds
from somarm.run import RunConfig, memory_needs
from somarm.validation import check_memory

__all__ = ["groups_of", "memory_at_seeds", "check_seeds"]

def groups_of(experiment: Callable[[Context], object]) -> Callable[[Context], dict[str, list[RunConfig]]] | None:
    """The ``groups`` of an experiment (a function of ``runner.EXPERIMENTS``): its module's, the one
    owner of its trial counts; None for one that declares none, as ``peers``, whose comparisons run
    one seed after another and keep only their numbers, so its memory does not grow with ``--seeds``."""
    from somarm.reproduce.experiment import Experiment

    if isinstance(experiment, Experiment):
        return experiment.groups
    return getattr(sys.modules[experiment.__module__], "groups", None)


def memory_at_seeds(experiment: Callable[[Context], object], *, quick: bool, seed: int, seeds: int,
                    backend: str) -> tuple[str, float]:
    """What ``experiment`` trains at each seed, and the bytes it needs at the seeds
    ``seed .. seed + seeds - 1``.

    The sum over its groups of ``run.memory_needs`` at one seed, times ``seeds`` (the estimate does
    not depend on the seed, so this equals the estimate of its groups at every seed).

    Args:
      experiment: one that declares its groups (``groups_of``).
      quick, seed, seeds, backend: as ``runner.reproduce`` takes them.

    Returns:
      ``(description, bytes)``: the description names each group's learners, trials and steps.

    Raises:
      ValueError: a run setting the learners refuse outright (one line).
    """
    ctx = Context(out_dir=Path(), quick=quick, seed=seed, progress=False, backend=backend, figures=False)
    ctx = experiment.context(ctx) if hasattr(experiment, "context") else ctx
    described, per_seed = [], 0.0
    for configs in groups_of(experiment)(ctx).values():
        what, n_bytes = memory_needs([config.resolved() for config in at_seeds(ctx, configs)])
        described.append(what)
        per_seed += n_bytes
    return "; ".join(described), per_seed * seeds


def check_seeds(experiments: dict[str, Callable[[Context], object]], *, quick: bool, seed: int, seeds: int,
                backend: str) -> None:
    """Refuse a reproduction whose training cannot fit in the memory available now, before anything
    is written: each experiment alone, as its groups check themselves (with ``--jobs`` several run
    at once, each in its own process).

    Raises:
      ValueError: one line naming ``--seeds N``, the experiment and what it trains, the size needed
        and the size available.
    """
    hint = " or ".join(["give fewer --seeds"] * (seeds > 1) + ["give --quick"] * (not quick)
                       + ["leave the experiment out (--only the others)"])
    for name, experiment in experiments.items():
        if groups_of(experiment) is not None:
            what, n_bytes = memory_at_seeds(experiment, quick=quick, seed=seed, seeds=seeds, backend=backend)
            check_memory(f"--seeds {seeds} ({name}: {what}, at each of {seeds} seed(s))", n_bytes, hint)
