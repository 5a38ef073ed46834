"""Figs. 21-23: varied target distance, three trials each with N_A = 25, 50 and 5 (train, measure, report)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from somarm import plots
from somarm.reproduce import metrics
from somarm.reproduce.common import Context, counted, final_error, fmt, preset_choices, run_group
from somarm.reproduce.experiment import Experiment
from somarm.reproduce.figures import legend_below, save, throw_action_map, unit_square
from somarm.reproduce.report import Claim, Section
from somarm.reproduce.throw import landing, solution_curve
from somarm.run import RunConfig, RunResult

__all__ = ["SIZES", "Trained", "groups", "train", "measure", "throw_maps"]

plt = plots.pyplot()

#: Each action neighbourhood N_A and the figure that shows it.
SIZES = ((25, 21), (50, 22), (5, 23))


@dataclass(frozen=True)
class Trained:
    """One neighbourhood's run and, per trial, what each input unit's greedy throw does."""

    result: RunResult
    targets: np.ndarray  #: ``(n_trials, n_input_units)`` the target each input unit serves
    landed: np.ndarray  #: ``(n_trials, n_input_units)`` where its greedy throw lands


def groups(ctx: Context) -> dict[str, list[RunConfig]]:
    """The runs this experiment trains at ``ctx.seed``, by label: Table 5 on throw_distance at each
    N_A (``SIZES``), three trials each."""
    n_steps = ctx.pick(10_000, 1_000)
    return {"Figs 21-23 N_A = 25, 50, 5": [
        RunConfig(task="throw_distance", preset="table5", overrides={"n_a": n_a}, n_trials=3, n_steps=n_steps,
                  seed=ctx.seed)
        for n_a, _ in SIZES
    ]}


def train(ctx: Context) -> dict[int, Trained]:
    """Table 5 on throw_distance at each N_A (``groups``); the greedy throws' landing points.

    Args:
      ctx: where and how the experiment runs (its seed, quick mode and backend).

    Returns:
      Each neighbourhood's run and greedy landing points, by N_A (``Trained``).

    Raises:
      KeyboardInterrupt: the training was stopped (see ``common.run_group``).
    """
    [(label, configs)] = groups(ctx).items()
    grouped = run_group(ctx, label, configs)
    trained = {}
    for (n_a, _), result in zip(SIZES, grouped, strict=True):
        learner = result.learner
        targets, landed = [], []
        for i in range(result.config.n_trials):
            actions = learner.action_weights[i][learner.q[i].argmax(axis=1)]
            targets.append(learner.input_weights[i, :, 0])
            landed.append(landing(actions[:, 0], actions[:, 1], backend=ctx.backend))
        trained[n_a] = Trained(result, np.array(targets), np.array(landed))
    return trained


def measure(trained: Trained) -> dict[str, np.ndarray]:
    """Per trial ``(n_trials,)``: gap CV of the interior input units, mean miss of the greedy throws,
    distinct greedy action units; and the final error of each trial over the last 1000 throws.

    Args:
      trained: one neighbourhood's ``Trained``.

    Returns:
      ``cv``, ``miss``, ``distinct`` and ``final``, each ``(n_trials,)``.
    """
    q = trained.result.learner.q
    cvs, misses = [], []
    for targets, landed in zip(trained.targets, trained.landed, strict=True):
        cvs.append(metrics.spacing_cv(targets[np.argsort(targets)][1:-1]))
        misses.append(np.abs(landed - targets).mean())
    return {"cv": np.array(cvs), "miss": np.array(misses),
            "distinct": np.array([len(np.unique(q[i].argmax(axis=1))) for i in range(len(q))]),
            "final": final_error(trained.result, 1000)}


def _claims(measured: dict[int, dict]) -> list[Claim]:
    all_cv = np.concatenate([m["cv"] for m in measured.values()])
    all_err = np.concatenate([m["miss"] for m in measured.values()])
    distinct = np.concatenate([m["distinct"] for m in measured.values()])
    means = {k: float(m["final"].mean()) for k, m in measured.items()}
    spread = max(means.values()) / min(means.values())
    return [
        Claim("Figs. 21-23: the input map spaces its 30 units equally over the targets.",
              f"gap coefficient of variation median {fmt(np.median(all_cv))} (max {fmt(all_cv.max())}) over "
              f"{len(all_cv)} trials.",
              bool(np.median(all_cv) <= 0.3), "median CV <= 0.3", values={"median CV": float(np.median(all_cv))}),
        Claim("Fig. 21: each input unit's greedy throw lands near the targets it serves.",
              f"mean |landing - unit's target| median {fmt(np.median(all_err))} (max {fmt(all_err.max())}); "
              f"the 30 input units use a median of {fmt(np.median(distinct))} distinct greedy throws, so "
              "neighbouring targets share a throw (the staircases of the right-hand plots).",
              bool(np.median(all_err) <= 0.25), "median <= 0.25", values={"median miss": float(np.median(all_err))}),
        Claim("Figs. 21-23: the three neighbourhood sizes perform alike.",
              "final error (last 1000 throws) " + ", ".join(f"N_A={k}: {fmt(v)}" for k, v in means.items())
              + f"; largest / smallest {fmt(spread)}.",
              bool(spread <= 1.5), "ratio <= 1.5", values={"largest / smallest": float(spread)}),
    ]


def _trial_row(axes, learner, i: int, targets: np.ndarray, landed: np.ndarray, miss: float) -> None:
    """One trial's input map, action map over the X = 4.5 curve, and greedy landing against target."""
    greedy = learner.q[i].argmax(axis=1)
    n_actions = learner.q.shape[2]
    plots.draw_input_map(axes[0], learner.input_weights[i] / 9.0, greedy, n_actions,
                         tuple(learner.config.input_shape), labels=("target (normalised)",))
    axes[0].set_title(f"trial {i}: input map (shaded by greedy action unit)", fontsize=9)
    throw_action_map(axes[1], solution_curve(X=4.5), learner.action_weights[i],
                     curve_style={"color": "0.85", "lw": 4, "label": "throws landing at 4.5"}, labels=("u_x", "u_y"))
    unit_square(axes[1])
    axes[1].set_title("action map (shaded by index)", fontsize=9)
    # The map's own lines carry no label (plots.draw_action_map): named here by stand-ins of their style.
    chain = plt.Line2D([], [], color="0.6", lw=0.7, label="neighbouring action units")
    unit = plt.Line2D([], [], ls="none", marker="o", markerfacecolor="0.7", markeredgecolor="k", label="action unit")
    axes[1].legend(handles=[*axes[1].get_legend_handles_labels()[0], chain, unit], fontsize=7,
                   **{**legend_below(ncol=3), "bbox_to_anchor": (0.5, -0.2)})  # below the u_x label
    index = np.arange(len(targets))
    axes[2].plot(index, targets, "k--", lw=0.8, label="target of the unit")
    axes[2].scatter(index, landed, c=plots.unit_colours(n_actions)[greedy], edgecolors="k", linewidths=0.4,
                    s=24, label="greedy throw lands", zorder=2)
    axes[2].set(xlabel="input unit index", ylabel="distance", ylim=(-0.5, 9.5))
    axes[2].set_title(f"landing of each unit's greedy throw (mean miss {miss:.3f})", fontsize=9)
    axes[2].legend(fontsize=7, loc="upper left")


def _figure(ctx: Context, n_a: int, fig_no: int, trained: Trained, miss: np.ndarray):
    """Fig. ``fig_no``: one row per trial of the run at action neighbourhood ``n_a``."""
    n_trials = len(trained.targets)
    fig, axes = plt.subplots(n_trials, 3, figsize=(12, 3.6 * n_trials), squeeze=False, layout="constrained")
    for i in range(n_trials):
        _trial_row(axes[i], trained.result.learner, i, trained.targets[i], trained.landed[i], miss[i])
    fig.suptitle(f"Fig. {fig_no}: throw_distance, action neighbourhood N_A = {n_a} x f(throw)")
    return save(ctx, fig, f"fig{fig_no}_throw_maps_na{n_a}.png")


def report(ctx: Context, trained) -> Section:
    """Figs. 21-23: varied target distance, three trials each with N_A = 25, 50 and 5."""
    measured = {n_a: measure(t) for n_a, t in trained.items()}
    config = trained[SIZES[0][0]].result.config
    section = Section("throw_maps", "Figs. 21-23: varied target distance, action neighbourhoods 25, 50, 5")
    section.choices += preset_choices("table5")
    section.choices += [
        f"{counted(config.n_trials, 'trial')} of {config.n_steps} throws per neighbourhood (f = 0.9985^throw is "
        "below 0.001 by throw 4600).",
        "Equal spacing: coefficient of variation of the gaps between the sorted input units, interior units "
        "only (the end units sit inside the range, as a SOM's do), at most 0.3.",
        "'Greedy throws land near their targets': mean |landing - input unit| at most 0.25 (targets span 9).",
        "'The three perform alike': the largest final error at most 1.5 times the smallest.",
    ]
    section.figures += [_figure(ctx, n_a, fig_no, trained[n_a], measured[n_a]["miss"]) for n_a, fig_no in SIZES]
    section.claims += _claims(measured)
    return section


throw_maps = Experiment(groups, train, report)
