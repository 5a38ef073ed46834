"""``sweep.png``: the greedy error against each swept parameter, with the spread over seeds.

Imported only when the figure is drawn, so a sweep without figures never loads matplotlib.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from somarm import plots
from somarm.sweep.spec import preset_value, same_value
from somarm.sweep.work import greedy_name

__all__ = ["draw"]

plt = plots.pyplot()


def _numbers(values: list[str]) -> np.ndarray | None:
    try:
        return np.array([float(v) for v in values])
    except ValueError:
        return None


def draw(table, path: Path) -> Path:
    """One panel per swept key: every seed (dots), each point's mean and seed sd (bars), the best.

    Args:
      table: a ``somarm.sweep.store.Table`` with at least one row.
      path: where the PNG goes (written atomically).
    """
    keys = table.keys
    fig, axes = plt.subplots(1, len(keys), figsize=(4.2 * len(keys), 3.4), squeeze=False, sharey=True)
    stats = table.per_point()
    best = table.best()
    for ax, key in zip(axes[0], keys, strict=True):
        labels = [p[key] for p in table.points]
        numbers = _numbers(labels)
        if numbers is None:  # categorical values: one slot each, in the order given
            order = list(dict.fromkeys(labels))
            position = {label: float(order.index(label)) for label in order}
            ax.set_xticks(range(len(order)), order, rotation=20)
        else:
            position = {label: float(label) for label in labels}
            positive = numbers[numbers > 0]
            if len(positive) == len(numbers) and positive.max() / positive.min() >= 20:
                ax.set_xscale("log")
        rows = [r for r in table.rows if not r.get("error")]
        ax.scatter([position[table.points[r["point"]][key]] for r in rows], [r["greedy_error"] for r in rows],
                   s=9, color="0.6", alpha=0.7, label="one seed", zorder=1)
        if stats:
            x = np.array([position[s["values"][key]] for s in stats])
            mean = np.array([s["greedy_error"] for s in stats])
            ax.errorbar(x, mean, yerr=[s["greedy_error_seed_sd"] for s in stats], fmt="o", color="C0",
                        ms=4, capsize=2, lw=0.8, label="mean over seeds (sd)", zorder=2)
            # The lower envelope: the best mean reached at each value of this key, whatever the others.
            xs = np.unique(x)
            ax.plot(xs, [mean[x == v].min() for v in xs], color="C0", lw=1.0, alpha=0.6, zorder=2)
        if best is not None:
            ax.scatter([position[best["values"][key]]], [best["greedy_error"]], marker="*", s=140,
                       color="C3", label="best", zorder=3)
        own = preset_value(table.spec, key)
        slot = next((position[label] for label in labels if own is not None and same_value(label, own)), None)
        if slot is None and own is not None and numbers is not None and _numbers([own]) is not None:
            slot = float(own)
        if slot is not None:
            ax.axvline(slot, color="0.3", ls="--", lw=0.8, label=f"preset {table.spec.preset}")
        ax.set_xlabel(key)
        ax.grid(alpha=0.3)
    name = greedy_name(table.spec.task)
    axes[0][0].set_ylabel(name if name != "greedy error" else "greedy error (fresh observations)")
    handles = {}
    for ax in axes[0]:
        for handle, label in zip(*ax.get_legend_handles_labels(), strict=True):
            handles.setdefault(label, handle)
    fig.legend(handles.values(), handles.keys(), fontsize=7, loc="upper center", ncol=len(handles) if len(keys) > 1 else 2,
               bbox_to_anchor=(0.5, -0.02), frameon=False)
    spec = table.spec
    fig.tight_layout()
    fig.suptitle(f"{spec.task} / {spec.learner}: {spec.n_trials} trials x {spec.n_steps} steps, "
                 f"{spec.n_seeds} seed(s)", fontsize=10, y=1.03)
    return plots.save(fig, path)
