"""The figure of ``somarm compare``: greedy error against samples and against wall time (log axes)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from somarm.plots import pyplot, save

__all__ = ["NAMES", "COLOURS", "compare_figure"]

#: How each learner is named in figures and tables.
NAMES = {"somq": "SOM-Q", "somq+": "SOM-Q+ (interpolated)", "motoric": "Motoric Map",
         "tabular": "tabular (fixed grid)", "td3": "SB3 TD3", "sac": "SB3 SAC"}
#: One colour per learner, the same in every figure.
COLOURS = {"somq": "C0", "somq+": "C5", "motoric": "C1", "tabular": "C2", "td3": "C3", "sac": "C4"}

plt = pyplot()


def compare_figure(result: dict[str, Any], path: str | Path) -> Path:
    """Two panels from a ``compare.json`` dict: median error (for a ``gym:ID`` task: return) over seeds
    (band: min to max).

    Left, against training samples; right, against training wall time (each seed's own times,
    their median per rung). The dashed line is the score of uniformly random actions.
    """
    metric = result.get("metric", "error")
    fig, (by_samples, by_time) = plt.subplots(1, 2, figsize=(11, 4.2), sharey=True)
    order = list(NAMES)  # the same legend order in every figure, also when read back from JSON
    counts = {kind: np.array(data[metric]).shape[1] for kind, data in result["learners"].items()}
    same = len(set(counts.values())) == 1  # else each learner's legend entry says how many seeds it has
    for kind, data in sorted(result["learners"].items(), key=lambda item: order.index(item[0])):
        errors = np.array(data[metric])  # (rungs, seeds)
        samples = np.array(data["samples"])
        walls = np.median(np.array(data["wall_seconds"]), axis=1)
        median, low, high = np.median(errors, axis=1), errors.min(axis=1), errors.max(axis=1)
        label = NAMES.get(kind, kind) + ("" if same else f" ({counts[kind]} seed{'' if counts[kind] == 1 else 's'})")
        for ax, x in ((by_samples, samples), (by_time, walls)):
            ax.plot(x, median, "o-", color=COLOURS.get(kind, "k"), label=label, ms=3)
            ax.fill_between(x, low, high, color=COLOURS.get(kind, "k"), alpha=0.15, lw=0)
    for ax in (by_samples, by_time):
        ax.axhline(result[f"random_action_{metric}"], color="grey", ls="--", lw=1, label="random actions")
        ax.set_xscale("log")
        if metric == "error":
            ax.set_yscale("log")
        ax.grid(True, which="both", alpha=0.3)
    by_samples.set_xlabel("training samples")
    by_time.set_xlabel("training wall time (s)")
    by_samples.set_ylabel(f"greedy error on {result['observations']} fresh observations" if metric == "error"
                          else f"greedy return per episode ({result['episodes']} fresh episodes at the end)")
    by_samples.legend(fontsize=8)
    over = f"{next(iter(counts.values()))} seeds" if same else "each learner's seeds"
    fig.suptitle(f"{result['task']}: median over {over} (band: min to max)")
    return save(fig, path)
