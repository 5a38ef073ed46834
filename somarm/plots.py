"""Figures of a training run: learning curve, input map and action map (matplotlib, headless).

Imported only when figures are written, so training without figures never loads matplotlib.
"""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np

from somarm.io import atomic_write_bytes

__all__ = ["pyplot", "save", "learning_curve", "moving_average", "unit_colours", "draw_input_map", "draw_action_map",
           "run_figures"]


def pyplot():
    """``matplotlib.pyplot`` on the headless Agg backend: how every figure module imports matplotlib.

    Returns:
      The ``matplotlib.pyplot`` module, its backend set to Agg before pyplot is first imported
      (so no display is needed).
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot

    return matplotlib.pyplot


plt = pyplot()


def save(fig: plt.Figure, path: str | Path, *, crop: bool = True) -> Path:
    """Save a figure as PNG (110 dpi) atomically and close it.

    Args:
      fig: the figure; closed once written.
      path: where the PNG goes.
      crop: trim the white margin to the drawn content (``bbox_inches="tight"``); False keeps the
        figure's own size.

    Returns:
      ``path``.

    Raises:
      ValueError: the file cannot be written (a full disk), in one line naming it.
    """
    buffer = io.BytesIO()
    title = _title_of(fig)
    fig.savefig(buffer, format="png", dpi=110, bbox_inches="tight" if crop else None,
                metadata={"Title": title} if title else None)
    plt.close(fig)
    return atomic_write_bytes(path, buffer.getvalue())


def _title_of(fig: plt.Figure) -> str:
    """The figure's title (its suptitle, else its first axes' title), written into the PNG so that a
    report's image link can describe the figure; "" when it has none."""
    return fig.get_suptitle() or next((ax.get_title() for ax in fig.axes if ax.get_title()), "")


def forward_filled(values: np.ndarray) -> np.ndarray:
    """``(n_blocks, n_trials)`` with each NaN replaced by the last number above it in its column
    (NaN until the first number)."""
    filled = np.array(values, dtype=np.float64)
    for row in range(1, len(filled)):
        gap = np.isnan(filled[row])
        filled[row, gap] = filled[row - 1, gap]
    return filled


def learning_curve(
    ax: plt.Axes,
    steps: np.ndarray,
    block_means: np.ndarray,
    *,
    window_blocks: int = 1,
    label: str = "mean over trials",
    color: str = "C0",
    per_trial: bool = False,
    error_bars: bool = True,
) -> None:
    """Mean reward over trials (moving average over ``window_blocks`` blocks) with sd error bars.

    Args:
      steps: ``(n_blocks,)`` step at the end of each block.
      block_means: ``(n_blocks, n_trials)`` mean reward per block.
    """
    smoothed = moving_average(block_means, window_blocks)
    if per_trial:
        ax.plot(steps, smoothed, color=color, alpha=0.35, lw=0.8)
    mean = smoothed.mean(axis=1)
    ax.plot(steps, mean, color=color, lw=1.8, label=label)
    if error_bars and smoothed.shape[1] > 1:
        every = max(1, len(steps) // 20)
        ax.errorbar(
            steps[::every],
            mean[::every],
            yerr=smoothed.std(axis=1)[::every],
            fmt="none",
            ecolor=color,
            capsize=2,
            lw=0.8,
        )


def moving_average(block_means: np.ndarray, window_blocks: int) -> np.ndarray:
    """Trailing mean over up to ``window_blocks`` blocks (shorter at the start), same shape."""
    window_blocks = max(1, int(window_blocks))
    cumulative = np.cumsum(np.vstack([np.zeros((1, block_means.shape[1])), block_means]), axis=0)
    ends = np.arange(1, len(block_means) + 1)
    starts = np.maximum(0, ends - window_blocks)
    return (cumulative[ends] - cumulative[starts]) / (ends - starts)[:, None]


def unit_colours(n: int) -> np.ndarray:
    """``n`` colours of the viridis map, from its first to its last, ``(n, 4)`` RGBA."""
    return plt.get_cmap("viridis")(np.linspace(0.0, 1.0, max(n, 1)))


def _grid_lines(ax: plt.Axes, points: np.ndarray, grid_shape: tuple[int, ...]) -> None:
    """Join neighbouring units of a 1-D or 2-D map (points are ``(n_units, 2)`` in row-major order)."""
    if len(grid_shape) == 2 and min(grid_shape) > 1:
        grid = points.reshape(*grid_shape, 2)
        for row in grid:
            ax.plot(row[:, 0], row[:, 1], color="0.6", lw=0.7, zorder=1)
        for col in grid.transpose(1, 0, 2):
            ax.plot(col[:, 0], col[:, 1], color="0.6", lw=0.7, zorder=1)
    else:
        ax.plot(points[:, 0], points[:, 1], color="0.6", lw=0.7, zorder=1)


def draw_input_map(
    ax: plt.Axes,
    weights: np.ndarray,
    greedy: np.ndarray,
    n_actions: int,
    grid_shape: tuple[int, ...],
    *,
    labels: tuple[str, str] = ("x", "y"),
    colourbar: str | None = None,
) -> None:
    """Input units in input space (first two dimensions), shaded by their greedy action unit.

    Args:
      weights: ``(n_input_units, obs_dim)``; a 1-D input space is drawn as unit index vs weight.
      greedy: ``(n_input_units,)`` index of each unit's greedy action unit.
      n_actions: how many action units the shades span (``unit_colours(n_actions)``).
      colourbar: the label of a colour bar beside the map, from action unit 0 to ``n_actions - 1``
        (None: no colour bar).
    """
    colours = unit_colours(n_actions)[greedy]
    if weights.shape[1] == 1:
        points = np.column_stack([np.arange(len(weights)), weights[:, 0]])
        labels = ("input unit index", labels[0])
    else:
        points = weights[:, :2]
    _grid_lines(ax, points, grid_shape)
    ax.scatter(points[:, 0], points[:, 1], c=colours, s=28, edgecolors="k", linewidths=0.4, zorder=2)
    ax.set_xlabel(labels[0])
    ax.set_ylabel(labels[1])
    if colourbar is not None:
        _unit_colourbar(ax, n_actions, colourbar)


def _unit_colourbar(ax: plt.Axes, n_units: int, label: str) -> None:
    """A colour bar for ``unit_colours(n_units)``: unit i has the shade at i / (n_units - 1)."""
    shades = plt.cm.ScalarMappable(norm=plt.Normalize(0, max(n_units - 1, 1)), cmap="viridis")
    bar = ax.figure.colorbar(shades, ax=ax, label=label, fraction=0.046, pad=0.04)
    bar.locator = plt.MaxNLocator(integer=True)
    bar.update_ticks()


def draw_action_map(
    ax: plt.Axes,
    weights: np.ndarray,
    low: np.ndarray,
    high: np.ndarray,
    *,
    labels: tuple[str, str] = ("action 1 (normalised)", "action 2 (normalised)"),
    normalise: bool = True,
    join: bool = True,
    periodic: np.ndarray | None = None,
) -> None:
    """Action units in (normalised) action space, shaded by their index in the map.

    2-D actions are drawn as points joined in map order (``join``); higher-dimensional ones as a
    heat map of unit index against action dimension. ``periodic`` (a bool per action dimension)
    marks dimensions whose low and high are one point (wrapped angles): a link between neighbours
    that crosses that seam the short way is left out rather than drawn across the whole plot.
    """
    values = (weights - low) / (high - low) if normalise else weights
    if values.shape[1] == 2:
        if join:
            line = values.astype(float)
            if periodic is not None and np.any(periodic):
                half = (np.asarray(high) - np.asarray(low)) / 2.0
                seam = (np.abs(np.diff(weights, axis=0)) > half)[:, np.asarray(periodic, dtype=bool)].any(axis=1)
                # A NaN row after each unit whose link to the next crosses the seam breaks the line there.
                line = np.insert(line, np.flatnonzero(seam) + 1, np.nan, axis=0)
            ax.plot(line[:, 0], line[:, 1], color="0.6", lw=0.7, zorder=1)
        ax.scatter(
            values[:, 0],
            values[:, 1],
            c=unit_colours(len(values)),
            s=28,
            edgecolors="k",
            linewidths=0.4,
            zorder=2,
        )
        ax.set_xlabel(labels[0])
        ax.set_ylabel(labels[1])
        if normalise:
            ax.set_xlim(-0.02, 1.02)
            ax.set_ylim(-0.02, 1.02)
    else:
        image = ax.imshow(
            values,
            aspect="auto",
            cmap="viridis",
            vmin=0 if normalise else None,
            vmax=1 if normalise else None,
            interpolation="nearest",
        )
        ax.figure.colorbar(image, ax=ax, label="normalised value" if normalise else "value")
        ax.set_xlabel("action dimension")
        ax.set_ylabel("action unit index")


def run_figures(result, out: Path) -> list[Path]:
    """The three figures of ``somarm train``: learning curve, input map, action map (the first trial).

    The maps show the run's first trial and name it by its trial id (``--trial-ids 7``: trial 7).
    """
    config, learner, task = result.config, result.learner, result.task
    first = int(config.trial_ids_array()[0])
    paths = []
    fig, ax = plt.subplots(figsize=(7, 4))
    window_blocks = max(1, min(1000, config.n_steps // 10) // config.block)
    returns = result.block_returns
    if returns is not None and np.isfinite(returns).any(axis=0).all():
        # A multi-step task's curve is in returns per episode: each block shows the episodes that
        # ended in it (a block where a trial finished none holds that trial's last value).
        shown = forward_filled(returns)
        first_full = int(np.argmax(np.isfinite(shown).all(axis=1)))
        learning_curve(ax, result.steps[first_full:], shown[first_full:], window_blocks=window_blocks,
                       per_trial=config.n_trials <= 30)
        ax.set_ylabel(f"return per episode (episodes ending in the last {window_blocks * config.block} steps)")
    else:
        learning_curve(
            ax, result.steps, result.block_means, window_blocks=window_blocks, per_trial=config.n_trials <= 30
        )
        ax.set_ylabel(f"mean reward (last {window_blocks * config.block} steps)")
    ax.set_xlabel("training step t")
    ax.set_title(
        f"{config.task}: {config.learner}, preset {config.preset}, {config.n_trials} trial(s), "
        f"seed {config.seed}"
    )
    ax.grid(alpha=0.3)
    ax.legend(loc="lower right")
    paths.append(save(fig, out / "learning_curve.png"))

    if not learner.has_maps:  # no maps to draw (the tabular learner's grids are fixed)
        return paths
    input_weights = np.asarray(learner.input_weights)[0]
    grid_shape = tuple(learner.config.input_shape)
    if learner.has_action_map:
        greedy = np.asarray(learner.q)[0].argmax(axis=1)
        n_actions = np.asarray(learner.q).shape[2]
    else:  # Motoric Map: each input unit owns its action; shade by unit index
        greedy = np.arange(len(input_weights))
        n_actions = len(input_weights)
    fig, ax = plt.subplots(figsize=(5, 5))
    from somarm import tasks  # the task's record names its axes

    record = tasks.record(config.task)
    observation_labels, action_labels = record.observation_labels, record.action_labels
    shade, units = ("greedy action unit", "action map") if learner.has_action_map else ("input unit", "input map")
    draw_input_map(ax, input_weights, greedy, n_actions, grid_shape, labels=(*observation_labels, "")[:2],
                   colourbar=f"{shade} (its index in the {units})")
    ax.set_title(f"input map (trial {first}), shaded by {shade}")
    paths.append(save(fig, out / "input_map.png"))

    fig, ax = plt.subplots(figsize=(5, 5))
    draw_action_map(
        ax,
        np.asarray(learner.action_weights)[0],
        task.action_low,
        task.action_high,
        labels=action_labels,
        join=learner.has_action_map,  # a Motoric Map's actions follow the input grid, not a chain
        periodic=learner.periodic_dimensions,
    )
    ax.set_title(
        f"action map (trial {first}), shaded by unit index"
        if learner.has_action_map
        else f"each input unit's action (trial {first}), shaded by input unit"
    )
    paths.append(save(fig, out / "action_map.png"))
    return paths
