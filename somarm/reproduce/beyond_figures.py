"""The figures of the beyond part: learning curves, greedy errors, and the response along a target sweep."""

from __future__ import annotations

import numpy as np

from somarm import plots
from somarm.learners.somq import RESPONSES
from somarm.reproduce.common import Context
from somarm.reproduce.figures import log_error_axes, save

__all__ = ["STYLE", "figures"]

plt = plots.pyplot()

#: One colour per response, the same in every figure.
STYLE = {"winner": "C0", "interpolated": "C1"}


def _label(preset: str, response: str) -> str:
    return f"{preset}, {response}"


def _curves(ctx: Context, results: dict, targets: dict):
    """Each task's training error curves, the target's preset dashed, the target level dotted."""
    tasks = list(dict.fromkeys(task for task, _, _ in results))
    fig, axes = plt.subplots(2, 2, figsize=(11, 7.5), layout="constrained")
    for ax, task in zip(axes.ravel(), tasks, strict=True):
        presets = list(dict.fromkeys(p for t, p, _ in results if t == task))
        for (t, preset, response), result in results.items():
            if t != task:
                continue
            error = -plots.moving_average(result.block_means, 10).mean(axis=1)
            ls = "-" if preset == presets[0] else "--"
            ax.plot(result.steps, error, ls=ls, color=STYLE[response], label=_label(preset, response))
        if task in targets:
            ax.axhline(targets[task][0], color="k", lw=0.8, ls=":", label=f"target (greedy) {targets[task][0]}")
        log_error_axes(ax, xlabel="step", ylabel="training error (mean over trials, 1000-step mean)", title=task,
                       legend={"fontsize": 8})
    fig.suptitle("Beyond the paper: learning curves, winner and interpolated responses "
                 "(training error includes the exploration noise)")
    return save(ctx, fig, "beyond_learning_curves.png")


def _greedy_bars(ctx: Context, greedy: dict, targets: dict):
    """One bar per run (mean greedy error over trials), its trials as dots, each target dotted."""
    fig, ax = plt.subplots(figsize=(11, 4.2), layout="constrained")
    keys = list(greedy)
    x = np.arange(len(keys))
    means = np.array([greedy[k].mean() for k in keys])
    ax.bar(x, means, color=[STYLE[k[2]] for k in keys], alpha=0.8)
    for i, key in enumerate(keys):
        trials = greedy[key]
        spread = np.linspace(-0.25, 0.25, trials.size) if trials.size > 1 else np.zeros(1)
        ax.plot(i + spread, trials, "k.", ms=3, label="one trial" if i == 0 else None)
        ax.text(i, max(means[i], trials.max()) * 1.08, f"{means[i]:.3f}", ha="center", va="bottom", fontsize=8)
        if key[0] in targets and key[1] == targets[key[0]][1]:
            ax.hlines(targets[key[0]][0], i - 0.45, i + 0.45, color="k", ls=":")
    ax.set_xticks(x, [f"{t}\n{p}\n{r}" for t, p, r in keys], fontsize=7)
    ax.set(yscale="log", ylabel="greedy error (bar: mean over trials)",
           title="Greedy error: winner (blue) and interpolated (orange) responses; dots: trials; "
                 "dotted: the targets")
    ax.legend(fontsize=8, loc="upper left")
    ax.grid(alpha=0.3, axis="y", which="both")
    return save(ctx, fig, "beyond_greedy_error.png")


def _response(ctx: Context, profiles: dict, targets: dict):
    """reach2: greedy fingertip error around the goal circle; throw_distance: landing against target."""
    fig, (left, right) = plt.subplots(1, 2, figsize=(12, 4.4), layout="constrained")
    trial, angles, errors = profiles["reach2"]
    for response in RESPONSES:
        left.plot(np.degrees(angles), errors[response], color=STYLE[response], lw=1,
                  label=f"{response} (mean {errors[response].mean():.4f})")
    left.set(xlabel="goal's angle on the circle (degrees)", ylabel="greedy fingertip error",
             title=f"reach2 ({targets['reach2'][1]}), trial {trial}: error around the goal circle")
    left.grid(alpha=0.3)
    left.legend(fontsize=8)
    trial, sweep, landing = profiles["throw_distance"]
    right.plot(sweep, sweep, color="0.6", lw=0.8, label="landing = target")
    for response in RESPONSES:
        right.plot(sweep, landing[response], color=STYLE[response], lw=1,
                   label=f"{response} (mean miss {np.abs(landing[response] - sweep).mean():.3f})")
    right.set(xlabel="target X", ylabel="landing x of the greedy throw",
              title=f"throw_distance ({targets['throw_distance'][1]}), trial {trial}: landing against target")
    right.grid(alpha=0.3)
    right.legend(fontsize=8)
    return save(ctx, fig, "beyond_response.png")


def figures(ctx: Context, results: dict, greedy: dict, profiles: dict, targets: dict) -> list:
    """The part's three figures, written into ``figures/``.

    Args:
      ctx: the experiment's context.
      results: the runs by (task, preset, response).
      greedy: their greedy errors ``(n_trials,)``, by the same keys.
      profiles: ``beyond.response_profiles``'s answer.
      targets: the targets, task -> (bound, preset).

    Returns:
      The three figures' paths.
    """
    return [_curves(ctx, results, targets), _greedy_bars(ctx, greedy, targets), _response(ctx, profiles, targets)]
