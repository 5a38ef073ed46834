"""What every experiment shares: the run context, training through ``somarm.run``, helpers."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from somarm import tasks
from somarm.reproduce.report import Section, merge_seeds
from somarm.run import RunConfig, RunResult, final_rewards, train_group
from somarm.run.split import train_split

__all__ = [
    "SPLIT_TRIAL_STEPS",
    "Context",
    "MOTORIC_CHOICE",
    "preset_choices",
    "run",
    "run_group",
    "at_seeds",
    "run_experiment",
    "typical_trial",
    "fit_circle",
    "final_error",
    "fmt",
    "counted",
]


#: A group of at least this many trial-steps trains in as many processes as there are threads
#: (``somarm.run.split``): the paper-scale groups of Figs. 13, 24 and 25 and of the beyond part (a
#: process's start-up, about 3 s, is not worth it for a quick run's groups).
SPLIT_TRIAL_STEPS = 1_000_000


@dataclass(frozen=True)
class Context:
    """Where and how an experiment runs.

    ``quick`` uses reduced trial counts and run lengths (a smoke test: verdicts are indicative only).
    With several ``seeds`` the experiment runs once per seed; its first training call trains every
    seed's configurations in one lockstep group and keeps the other seeds' results in ``trained``
    for their turn. Only the first seed draws figures.
    """

    out_dir: Path
    quick: bool = False
    seed: int = 0
    progress: bool = True
    backend: str = "mujoco"  #: where every reward is computed: "mujoco" or "analytic"
    seeds: tuple[int, ...] = ()  #: every seed of the run (empty: just ``seed``)
    figures: bool = True  #: draw and write the figures (the first seed does)
    trained: dict = field(default_factory=dict, compare=False, repr=False)

    def pick(self, full, quick):
        """The paper-scale value, or the reduced one in quick mode."""
        return quick if self.quick else full

    def path(self, name: str) -> Path:
        """Where the figure ``name`` goes: ``figures/name`` in the output folder."""
        return self.out_dir / "figures" / name


def run(ctx: Context, label: str, config: RunConfig, *, snapshots_at: tuple[int, ...] = ()) -> RunResult:
    """Train one configuration (every evaluation through ``ctx.backend``)."""
    return run_group(ctx, label, [config], snapshots_at=snapshots_at)[0]


def run_group(
    ctx: Context, label: str, configs: list[RunConfig], *, snapshots_at: tuple[int, ...] = ()
) -> list[RunResult]:
    """Train configurations in lockstep (one physics call per step for all) at this context's seed.

    With several ``ctx.seeds``, the first call for ``label`` trains the configurations at every
    seed in one group; the other seeds' results wait in ``ctx.trained``. Each result equals a
    run of its configuration alone.

    Raises:
      KeyboardInterrupt: the training was stopped (Ctrl-C or SIGTERM stop it between steps); an
        experiment must not go on to draw conclusions from a partial run, so the reproduction stops.
    """
    if (label, ctx.seed) not in ctx.trained:
        seeds = ctx.seeds or (ctx.seed,)
        group = at_seeds(ctx, configs)
        processes = tasks.threads() if sum(c.n_trials * c.n_steps for c in group) >= SPLIT_TRIAL_STEPS else 1
        if processes > 1:  # a long group: its configs shared out between processes (no shared GIL)
            results = train_split(group, processes=processes, progress=ctx.progress, label=label,
                                  snapshots_at=snapshots_at)
        else:
            results = train_group(group, progress=ctx.progress, label=label, snapshots_at=snapshots_at)
        if any(result.interrupted for result in results):
            raise KeyboardInterrupt
        for i, s in enumerate(seeds):
            ctx.trained[(label, s)] = results[i * len(configs):(i + 1) * len(configs)]
    return ctx.trained.pop((label, ctx.seed))


def at_seeds(ctx: Context, configs: list[RunConfig]) -> list[RunConfig]:
    """The lockstep group ``run_group`` trains for ``configs``: each at every seed of the run (seed by
    seed, in order), its rewards through ``ctx.backend`` where the task has it."""
    seeds = ctx.seeds or (ctx.seed,)
    return [dataclasses.replace(c, seed=s, backend=_backend(c.task, ctx.backend)) for s in seeds for c in configs]


def _backend(task: str, backend: str) -> str:
    """``backend`` where the task has it; MuJoCo for a task without closed forms (reach2_obstacle)."""
    return backend if backend in tasks.record(task).backends else "mujoco"


def preset_choices(*names: str) -> list[str]:
    """The choices the named presets make where their tables are silent, as report lines."""
    from somarm.learners import presets

    return [
        f"Preset `{name}` ({presets.PRESETS[name].description.split(':')[0]}): {choice}."
        for name in names
        for choice in presets.PRESETS[name].choices
    ]


#: How the Motoric Map baseline reads the paper's one sentence about it.
MOTORIC_CHOICE = (
    "Motoric Map (graph B): each input unit keeps one action and a value; the action is copied and perturbed "
    "as in SOM-Q; when the reward beats the unit's value, the actions move towards the perturbed action over "
    "an input-grid neighbourhood N_A = 3 f(t) (Table 2's number; as in Ritter, Martinetz and Schulten's motor "
    "maps; N_A = 0 would make them strictly private, which barely moves in 40,000 steps); values move by "
    "alpha over the input neighbourhood."
)


def final_error(result: RunResult, window: int) -> np.ndarray:
    """Each trial's mean error (minus reward) over the last ``window`` steps, ``(n_trials,)``."""
    return -final_rewards(result.block_means, result.config.block, window)


def fit_circle(points: np.ndarray) -> tuple[np.ndarray, float]:
    """Centre ``(2,)`` and radius of the goal circle, read off the task's own goal samples ``(n, 2)``."""
    centre = points.mean(axis=0)
    return centre, float(np.linalg.norm(points - centre, axis=1).mean())


def typical_trial(errors: np.ndarray) -> int:
    """The trial with the median final error (the paper shows 'a typical trial')."""
    return int(np.argsort(errors)[len(errors) // 2])


def fmt(x: float, digits: int = 3) -> str:
    """A number for the report, in fixed notation where sensible."""
    if not np.isfinite(x):
        return "never" if np.isnan(x) else str(x)
    if float(x).is_integer() and abs(x) < 1e7:
        return str(int(x))
    return f"{x:.{digits}g}" if abs(x) < 1e-3 or abs(x) >= 1e4 else f"{x:.{digits}f}"


def counted(n: int, noun: str) -> str:
    """``n`` with its noun, plural unless ``n`` is one: ``counted(1, "trial")`` is "1 trial", 4 give "4 trials"."""
    return f"{n} {noun}" if n == 1 else f"{n} {noun}s"


def run_experiment(experiment: Callable[[Context], Section], out: Path, *, quick: bool, seeds: tuple[int, ...],
                   progress: bool, backend: str) -> Section:
    """An experiment at every seed (one lockstep training for all seeds, consumed seed by seed), its
    figures (the first seed's) written into ``out/figures``; the seeds' sections merged when there
    are several."""
    trained: dict = {}
    parts = [
        experiment(Context(out_dir=out, quick=quick, seed=s, progress=progress, backend=backend,
                           seeds=seeds if len(seeds) > 1 else (), figures=i == 0, trained=trained))
        for i, s in enumerate(seeds)
    ]
    return parts[0] if len(seeds) == 1 else merge_seeds(parts, list(seeds))
