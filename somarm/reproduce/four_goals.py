"""Figs. 13-15: four goals by quadrant, moved mid-run; SOM-Q against the Motoric Map."""

from __future__ import annotations

import numpy as np

from somarm import plots
from somarm.reproduce import metrics
from somarm.reproduce.common import (
    MOTORIC_CHOICE,
    Context,
    counted,
    fmt,
    preset_choices,
    run_group,
    typical_trial,
)
from somarm.reproduce.experiment import Experiment
from somarm.reproduce.figures import save, unit_square
from somarm.reproduce.report import Claim, Section
from somarm.run import RunConfig, RunResult, evaluation

__all__ = ["KINDS", "switch_step", "groups", "train", "phase_errors", "edge_counts", "four_goals"]

plt = plots.pyplot()

#: The two learners compared, SOM-Q (graph A) and the Motoric Map (graph B).
KINDS = ("somq", "motoric")


def switch_step(ctx: Context) -> int:
    """The step at which the goals move (20,000; 1,500 when quick); the run is twice as long."""
    return ctx.pick(20_000, 1_500)


def groups(ctx: Context) -> dict[str, list[RunConfig]]:
    """The runs this experiment trains at ``ctx.seed``, by label: both learners (``KINDS``) on four_goals
    with Table 2, the goals moved at ``switch_step``."""
    n_trials, switch = ctx.pick(20, 4), switch_step(ctx)
    return {"Fig 13 four_goals": [
        RunConfig(task="four_goals", learner=kind, preset="table2", n_trials=n_trials, n_steps=2 * switch,
                  seed=ctx.seed, task_params={"switch_step": switch})
        for kind in KINDS
    ]}


def train(ctx: Context) -> dict[str, RunResult]:
    """Both learners on four_goals (``groups``), with a snapshot where the goals move.

    Args:
      ctx: where and how the experiment runs (its seed, quick mode and backend).

    Returns:
      Each learner's run, by kind (``KINDS``).

    Raises:
      KeyboardInterrupt: the training was stopped (see ``common.run_group``).
    """
    [(label, configs)] = groups(ctx).items()
    return dict(zip(KINDS, run_group(ctx, label, configs, snapshots_at=(switch_step(ctx),)), strict=True))


def phase_errors(steps: np.ndarray, block_means: np.ndarray, switch: int, early: int) -> dict[str, float]:
    """Mean error (minus reward) over the first ``early`` steps of each phase and over the whole phase.

    Args:
      steps: ``(n_blocks,)`` the step at the end of each block.
      block_means: ``(n_blocks, n_trials)`` mean reward per block.

    Returns:
      ``{"before early", "before whole", "after early", "after whole"}``.
    """
    early_blocks = {"before": steps <= early, "after": (steps > switch) & (steps <= switch + early)}
    whole_blocks = {"before": steps <= switch, "after": steps > switch}
    errors = {}
    for phase in ("before", "after"):
        errors[f"{phase} early"] = -block_means[early_blocks[phase]].mean()
        errors[f"{phase} whole"] = -block_means[whole_blocks[phase]].mean()
    return errors


#: A trial's action map has piled at the edge when at least this share of its units is there.
_PILED = 0.9


def edge_counts(somq: RunResult, seed: int, n_observations: int) -> dict[str, int]:
    """SOM-Q's trials at the end of the run: how many failed (greedy error on fresh observations above
    twice the median over trials), and how many of those have their action units piled at the -pi
    edge of the paper's box (``metrics.edge_share`` of at least 90%).

    Returns:
      ``{name: count}``, the names as the report prints them.
    """
    greedy = -evaluation.evaluate_greedy(somq.learner, somq.task, n_observations=n_observations, seed=seed)
    failed = metrics.failed_trials(greedy)
    piled = metrics.edge_share(somq.learner.action_weights, somq.task.action_low) >= _PILED
    return {"SOM-Q trials failed at the end (greedy error above twice the median)": int(failed.sum()),
            f"of them with {100 * _PILED:g}% or more of their action units within {metrics.EDGE_WIDTH} rad of -pi":
            int((failed & piled).sum())}


def _claim(errors: dict[str, dict[str, float]]) -> Claim:
    somq, motoric = errors["somq"], errors["motoric"]
    measured = [
        f"{phase} the change: early error SOM-Q {fmt(somq[f'{phase} early'])} vs Motoric Map "
        f"{fmt(motoric[f'{phase} early'])} (whole phase {fmt(somq[f'{phase} whole'])} vs "
        f"{fmt(motoric[f'{phase} whole'])})"
        for phase in ("before", "after")
    ]
    early = {}
    for phase in ("before", "after"):
        early.update({f"SOM-Q {phase}": float(somq[f"{phase} early"]),
                      f"Motoric Map {phase}": float(motoric[f"{phase} early"])})
    return Claim(
        "Fig. 13: SOM-Q learns faster than the Motoric Map both before and after the environment change.",
        "; ".join(measured) + ".",
        all(bool(somq[f"{phase} early"] < motoric[f"{phase} early"]) for phase in ("before", "after")),
        "SOM-Q's early error lower in both phases",
        values=early,
    )


def _curves_figure(ctx: Context, runs: dict[str, RunResult], switch: int):
    """Fig. 13: both learners' mean reward, the move marked."""
    fig, ax = plt.subplots(figsize=(7.5, 4.2))
    for colour, (name, label) in zip(("C0", "C3"), (("somq", "A: SOM-Q"), ("motoric", "B: Motoric Map")),
                                     strict=True):
        plots.learning_curve(ax, runs[name].steps, runs[name].block_means, label=label, color=colour,
                             error_bars=False)
    ax.axvline(switch, color="k", ls="--", lw=0.8, label="goals move")
    n_trials = runs["somq"].block_means.shape[1]
    ax.set(xlabel="time step t", ylabel="reward (mean over previous 100 steps)",
           title=f"Fig. 13: four goals, mean over {n_trials} trials (Table 2)")
    ax.grid(alpha=0.3)
    ax.legend(loc="lower right")
    return save(ctx, fig, "fig13_four_goals.png")


def _map_figures(ctx: Context, somq: RunResult, switch: int) -> list:
    """Figs. 14-15: SOM-Q's maps at the move, of the trial with the median error just before it."""
    from somarm.tasks import four_goals as task_module

    snap = somq.snapshots.get(switch)
    if snap is None:
        return []
    i = typical_trial(-somq.block_means[somq.steps <= switch][-10:].mean(axis=0))
    fig, ax = plt.subplots(figsize=(5.2, 5))
    plots.draw_input_map(ax, snap["input_weights"][i], snap["q"][i].argmax(axis=1), snap["q"].shape[2],
                         tuple(somq.learner.config.input_shape), labels=("input x", "input y"))
    ax.axhline(0.5, color="0.4", lw=0.8)
    ax.axvline(0.5, color="0.4", lw=0.8)
    goals = np.asarray(task_module.GOALS_BEFORE)
    ax.plot(goals[:, 0], goals[:, 1], "r+", ms=12, mew=2, label="goals (before the move)")
    unit_square(ax, title=f"Fig. 14: input map at t = {switch} (trial {i})")
    ax.legend(loc="upper right", fontsize=8)
    paths = [save(ctx, fig, "fig14_four_goals_input_map.png")]
    fig, ax = plt.subplots(figsize=(5.2, 5))
    plots.draw_action_map(ax, snap["action_weights"][i], somq.task.action_low, somq.task.action_high,
                          labels=("theta1 (normalised)", "theta2 (normalised)"))
    ax.set(aspect="equal", title=f"Fig. 15: action map at t = {switch} (trial {i})")
    return [*paths, save(ctx, fig, "fig15_four_goals_action_map.png")]


def report(ctx: Context, runs) -> Section:
    """Figs. 13-15: four goals by quadrant, moved mid-run; SOM-Q against the Motoric Map."""
    switch, early = switch_step(ctx), ctx.pick(5000, 500)
    errors = {kind: phase_errors(r.steps, r.block_means, switch, early) for kind, r in runs.items()}
    config = runs["somq"].config
    section = Section("four_goals", f"Figs. 13-15: four goals, moved at t = {switch:,} (Table 2)")
    section.choices += preset_choices("table2")
    section.choices.append(MOTORIC_CHOICE)
    section.choices += [
        f"{counted(config.n_trials, 'trial')} of {config.n_steps:,} steps, goals moved at t = {switch:,}; goal "
        "positions before and after the move are this project's (see the task).",
        f"'Learns faster' is measured as the mean error over the first {early:,} steps of each phase "
        "and over the whole phase.",
    ]
    section.claims.append(_claim(errors))
    section.counts.update(edge_counts(runs["somq"], ctx.seed, ctx.pick(1000, 100)))
    section.notes.append("Counted below: SOM-Q's trials whose greedy error ends above twice the median, and how many "
                         "of them failed because their action map piled against the -pi edge of the paper's box of "
                         "joint angles (90% or more of their units within 0.06 rad of it).")
    section.figures.append(_curves_figure(ctx, runs, switch))
    section.figures += _map_figures(ctx, runs["somq"], switch)
    return section


four_goals = Experiment(groups, train, report)
