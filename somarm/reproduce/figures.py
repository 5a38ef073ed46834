"""The report's figure helpers: writing a figure, and the drawings several experiments share.

Matplotlib comes in through ``somarm.plots.pyplot`` (headless), here as in every module that draws.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from somarm import plots
from somarm.reproduce.common import Context

__all__ = ["save", "unit_square", "goal_circle", "schedule_overlay", "throw_action_map", "log_error_axes",
           "legend_below"]

plt = plots.pyplot()


def save(ctx: Context, fig, name: str, *, crop: bool = True) -> Path:
    """Write a figure to ``figures/name`` and close it (only close it when this seed draws none).

    Args:
      ctx: the experiment's context (its folder, and whether this seed writes figures).
      fig: the figure.
      name: the PNG's file name.
      crop: trim the margin to the drawn content (see ``somarm.plots.save``).

    Returns:
      The figure's path, also when it was not written.

    Raises:
      ValueError: the figure cannot be written (a full disk), in one line naming it.
    """
    if not ctx.figures:
        plt.close(fig)
        return ctx.path(name)
    return plots.save(fig, ctx.path(name), crop=crop)


def unit_square(ax, **more) -> None:
    """Show the unit square at equal scale (the reach tasks' plane, the throws' velocity square);
    ``more``: further axes settings (labels, title)."""
    ax.set(xlim=(0, 1), ylim=(0, 1), aspect="equal", **more)


def goal_circle(ax, centre: np.ndarray, radius: float, *, colour: str, label: str | None = None) -> None:
    """The reach tasks' goal circle, dashed and unfilled (``label``: its legend entry, if any)."""
    style = {"label": label} if label is not None else {}
    ax.add_patch(plt.Circle(centre, radius, fill=False, ls="--", color=colour, **style))


def schedule_overlay(ax, steps: np.ndarray, decay, label: str) -> None:
    """f(t) on a second y axis, with one legend for both axes (so neither hides the other).

    Args:
      ax: the axes of a learning curve over ``steps``.
      steps: ``(n_blocks,)`` steps at which ``decay`` is drawn.
      decay: the annealing schedule, a callable of the step.
      label: its legend entry.
    """
    twin = ax.twinx()
    twin.plot(steps, decay(steps), ls=":", color="k", label=label)
    twin.set_ylabel("annealing schedule f(t)")
    twin.set_ylim(0, 1.05)
    handles, labels = ax.get_legend_handles_labels()
    more_handles, more_labels = twin.get_legend_handles_labels()
    twin.legend(handles + more_handles, labels + more_labels, loc="center right")


def throw_action_map(ax, curve: np.ndarray, units: np.ndarray, *, curve_style: dict,
                     labels: tuple[str, str]) -> None:
    """A throw's action units in the velocity square over a curve of equal landing point.

    Args:
      ax: the axes.
      curve: ``(n, 2)`` the curve in (u_x, u_y), NaN outside the square.
      units: ``(n_action_units, 2)`` the action units in (u_x, u_y).
      curve_style: how the curve is drawn (colour, width, label).
      labels: the axes' labels.
    """
    ax.plot(curve[:, 0], curve[:, 1], **curve_style)
    plots.draw_action_map(ax, units, np.zeros(2), np.ones(2), normalise=False, labels=labels)


def legend_below(ncol: int = 2) -> dict:
    """``ax.legend`` settings that put the legend under the axes (below the x label), where it hides
    no curve however the curves run."""
    return {"loc": "upper center", "bbox_to_anchor": (0.5, -0.14), "ncol": ncol, "frameon": False}


def log_error_axes(ax, *, xlabel: str, ylabel: str, title: str, legend: dict | None = None) -> None:
    """Label error curves drawn on ``ax``: a log y axis, a grid on both scales, a legend."""
    ax.set(xlabel=xlabel, ylabel=ylabel, yscale="log", title=title)
    ax.grid(alpha=0.3, which="both")
    ax.legend(**(legend or {}))
