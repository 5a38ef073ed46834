"""Figs. 16-20: throwing at one target X = 4 with Table 4 (train, measure, report)."""

from __future__ import annotations

import numpy as np

from somarm.plots import pyplot
from somarm.reproduce import metrics
from somarm.reproduce.common import Context, counted, final_error, fmt, preset_choices, run, typical_trial
from somarm.reproduce.experiment import Experiment
from somarm.reproduce.figures import save, throw_action_map, unit_square
from somarm.reproduce.report import Claim, Section
from somarm.run import RunConfig, RunResult
from somarm.tasks import ballistics

__all__ = ["TABLE3", "TARGET_X", "solution_curve", "landing", "groups", "train", "unit_spread", "ends",
           "steepness", "trajectories", "throw"]

plt = pyplot()

#: Table 3's environment.
TABLE3 = {"M": 1.0, "G": 0.05, "Fr": 0.1, "W": 0.0}
TARGET_X = 4.0


def solution_curve(n: int = 2001, *, X: float = TARGET_X, **env) -> np.ndarray:
    """Eq. 8's solution curve inside the velocity square, ``(n, 2)`` of (u_x, u_y), NaN outside."""
    env = {**TABLE3, **env}
    uy = np.linspace(0.0, 1.0, n)
    ux = ballistics.solution_ux(uy, X=X, **env)
    ux = np.where((ux >= 0) & (ux <= 1), ux, np.nan)
    return np.column_stack([ux, np.where(np.isfinite(ux), uy, np.nan)])


def landing(ux: np.ndarray, uy: np.ndarray, *, backend: str, **env) -> np.ndarray:
    """Landing x of throws, simulated in MuJoCo (the tasks' default backend) or from Eq. 7."""
    from somarm.tasks import throw as throw_task

    return throw_task.landing_x(ux, uy, params=throw_task.ThrowParams(**{**TABLE3, **env}), backend=backend)


def groups(ctx: Context) -> dict[str, list[RunConfig]]:
    """The run this experiment trains at ``ctx.seed``, by its label: Table 4 on the throw task."""
    n_trials, n_steps = ctx.pick(20, 4), ctx.pick(4000, 1500)
    return {"Figs 16-20 throw": [RunConfig(task="throw", preset="table4", n_trials=n_trials, n_steps=n_steps,
                                           seed=ctx.seed)]}


def train(ctx: Context) -> RunResult:
    """Table 4 on the throw task (``groups``), with snapshots of the action map along the run.

    Args:
      ctx: where and how the experiment runs (its seed, quick mode and backend).

    Returns:
      The run, with snapshots at throws 1, 20, 500, 4000 (those before its end) and at its end.

    Raises:
      KeyboardInterrupt: the training was stopped (see ``common.run_group``).
    """
    [(label, [config])] = groups(ctx).items()
    spans_at = tuple(t for t in (1, 20, 500, 4000) if t < config.n_steps) + (config.n_steps,)
    return run(ctx, label, config, snapshots_at=spans_at)


def unit_spread(units: np.ndarray, curve: np.ndarray) -> dict[str, np.ndarray]:
    """Where the action units ``(n_trials, n_units, 2)`` lie against the solution ``curve``.

    Args:
      units: ``(n_trials, n_units, 2)`` in (u_x, u_y).
      curve: ``solution_curve``'s answer.

    Returns:
      ``distances`` ``(n_trials, n_units)`` to the curve, ``coverage`` ``(n_trials,)`` the share of
      the curve's u_y range the units span, and the curve's lowest and highest u_y.
    """
    distances = np.stack([metrics.distance_to_polyline(u, curve) for u in units])
    valid = curve[np.isfinite(curve[:, 1])]
    uy_low, uy_high = valid[:, 1].min(), valid[:, 1].max()
    coverage = (units[:, :, 1].max(axis=1) - units[:, :, 1].min(axis=1)) / (uy_high - uy_low)
    return {"distances": distances, "coverage": coverage, "uy_low": uy_low, "uy_high": uy_high}


def ends(units: np.ndarray, uy_low: float, uy_high: float) -> dict:
    """The gaps between the units and the curve's two ends, and the verdict on 'lowest throws avoided'.

    The verdict is True when the low-end gap exceeds 0.02 and the high-end gap in >= 75% of trials,
    undecided (None) when only the first holds (both ends are left out: the bunched map cannot show
    a preference), False otherwise.

    Args:
      units: ``(n_trials, n_units, 2)`` in (u_x, u_y).
      uy_low, uy_high: the curve's lowest and highest u_y.

    Returns:
      ``low_gaps`` and ``high_gaps`` ``(n_trials,)``, the shares ``low_avoided`` and ``low_more``, ``verdict``.
    """
    low_gaps = units[:, :, 1].min(axis=1) - uy_low
    high_gaps = uy_high - units[:, :, 1].max(axis=1)
    low_avoided = (low_gaps > 0.02).mean()
    low_more = (low_gaps > high_gaps).mean()
    verdict = (True if low_more >= 0.75 else None) if low_avoided >= 0.75 else False
    return {"low_gaps": low_gaps, "high_gaps": high_gaps, "low_avoided": low_avoided, "low_more": low_more,
            "verdict": verdict}


def steepness(uy_low: float, uy_high: float) -> dict[str, np.ndarray]:
    """Eq. 7's landing point over the velocity square (201 x 201), its gradient's magnitude, and the
    mean magnitude near the target curve's low and high ends (within 0.1 in u_y).

    Args:
      uy_low, uy_high: the target curve's lowest and highest u_y.

    Returns:
      ``ux``, ``uy``, ``landing``, ``slope`` (each ``(201, 201)``), ``low_end`` and ``high_end``.
    """
    grid = np.linspace(0.0, 1.0, 201)
    ux, uy = np.meshgrid(grid, grid)
    landed = ballistics.landing_x(ux, uy, **TABLE3)
    d_uy, d_ux = np.gradient(landed, grid, grid)
    slope = np.hypot(d_ux, d_uy)
    on = np.abs(landed - TARGET_X) < 0.05
    return {"ux": ux, "uy": uy, "landing": landed, "slope": slope,
            "low_end": slope[on & (uy < uy_low + 0.1)].mean(), "high_end": slope[on & (uy > uy_high - 0.1)].mean()}


def _claims(spread: dict, gaps: dict, slopes: dict) -> list[Claim]:
    distances, coverage = spread["distances"], spread["coverage"]
    on_curve = (distances <= 0.02).mean()
    low_gaps, high_gaps = gaps["low_gaps"], gaps["high_gaps"]
    low_end, high_end = slopes["low_end"], slopes["high_end"]
    return [
        Claim(
            "Figs. 17-18: the action units spread along the analytic solution curve of Eq. 8.",
            f"median unit distance to the curve {fmt(np.median(distances))}; {100 * on_curve:.0f}% of units "
            f"within 0.02; the units span a median {100 * np.median(coverage):.0f}% of the curve's u_y range.",
            bool(on_curve >= 0.8 and np.median(coverage) >= 0.5),
            ">= 80% of units within 0.02, span >= 50%",
            values={"units within 0.02": float(on_curve), "median span": float(np.median(coverage))},
        ),
        Claim(
            "Fig. 17: the lowest, hardest throws are avoided (for their unreliability, more than other throws).",
            f"the lowest unit sits a median {fmt(np.median(low_gaps))} in u_y above the curve's low end "
            f"(u_y = {fmt(spread['uy_low'])}), gap > 0.02 in {100 * gaps['low_avoided']:.0f}% of trials; but the "
            f"highest unit also stops a median {fmt(np.median(high_gaps))} below the curve's high end, and the "
            f"low end is the larger gap in only {100 * gaps['low_more']:.0f}% of trials.",
            gaps["verdict"],
            "low-end gap > 0.02 and larger than the high-end gap in >= 75% of trials "
            "(undecided when only the first holds)",
            values={"low-end gap > 0.02": float(gaps["low_avoided"]), "low end the larger gap": float(gaps["low_more"])},
        ),
        Claim(
            "Figs. 19-20: along the target curve the landing point changes fastest for the lowest, hardest throws.",
            f"mean gradient magnitude of the landing point near the curve's low end {fmt(low_end)} vs its high "
            f"end {fmt(high_end)} (ratio {fmt(low_end / high_end)}).",
            bool(low_end > high_end),
            "low-end gradient > high-end gradient",
            values={"gradient ratio": float(low_end / high_end)},
        ),
    ]


def _bunching_note(spans: dict[int, float]) -> str:
    return (
        "Why the units bunch: the median u_y span of the action map at "
        + ", ".join(f"throw {t}: {fmt(v, 2)}" for t, v in spans.items())
        + ". With lambda_A = 1 and N_A = 15 at the start, each improving perturbation pulls most of the map "
        "onto one point; afterwards the SOM pull between neighbours (N_A >= 2) contracts the chain, and along a "
        "curve of equal reward nothing in the update rule pushes units apart, so they find the curve but not "
        "its length."
    )


def trajectories(curve: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
    """Two throws of the solution ``curve`` that land at X = 4, a sixth in from either end, simulated.

    Args:
      curve: ``solution_curve``'s answer.

    Returns:
      ``(u, path)`` per throw: the velocity ``(2,)`` and the flight's ``(n, 2)`` positions.
    """
    from somarm.tasks import throw as throw_task

    valid = curve[np.isfinite(curve[:, 1])]
    throws = []
    for point in (valid[len(valid) // 6], valid[-len(valid) // 6]):
        _, xy = throw_task.simulate_trajectory(point[0], point[1], throw_task.ThrowParams(**TABLE3))
        throws.append((point, xy))
    return throws


def _trajectories_figure(ctx: Context, throws: list[tuple[np.ndarray, np.ndarray]]):
    """Fig. 16: the two simulated throws of ``trajectories``."""
    fig, ax = plt.subplots(figsize=(7, 3.8))
    for (point, xy), colour in zip(throws, ("C0", "C3"), strict=True):
        ax.plot(xy[:, 0], xy[:, 1], color=colour, label=f"u = ({point[0]:.2f}, {point[1]:.2f})")
    ax.axhline(0, color="k", lw=0.8)
    ax.plot([TARGET_X], [0], "kv", ms=9, label="target X = 4")
    ax.set(xlabel="horizontal position s_x", ylabel="height s_y",
           title="Fig. 16: two trajectories to X = 4 (simulated in MuJoCo)")
    ax.legend()
    return save(ctx, fig, "fig16_throw_trajectories.png")


def _action_map_figure(ctx: Context, curve: np.ndarray, units: np.ndarray, i: int, n_steps: int):
    """Figs. 17-18: trial ``i``'s action units ``(n_units, 2)`` over the solution curve."""
    fig, ax = plt.subplots(figsize=(5.2, 5))
    throw_action_map(ax, curve, units, curve_style={"color": "k", "ls": "-", "lw": 1,
                                                    "label": "Eq. 8 solution curve"},
                     labels=("horizontal speed u_x", "vertical speed u_y"))
    unit_square(ax, title=f"Figs. 17-18: action map after {n_steps} throws (trial {i})")
    ax.legend(loc="upper right")
    return save(ctx, fig, "fig17_throw_action_map.png")


def _landing_figures(ctx: Context, curve: np.ndarray, slopes: dict) -> list:
    """Figs. 19-20: the landing point and its steepness over the velocity square."""
    paths = []
    for name, values, label, title in (
        ("fig19_landing.png", slopes["landing"], "landing position s_x", "Fig. 19: landing position"),
        ("fig20_landing_gradient.png", slopes["slope"], "|d s_x / d u|", "Fig. 20: steepness of the landing position"),
    ):
        fig, ax = plt.subplots(figsize=(5.6, 5))
        image = ax.contourf(slopes["ux"], slopes["uy"], values, levels=20, cmap="viridis")
        fig.colorbar(image, ax=ax, label=label)
        ax.plot(curve[:, 0], curve[:, 1], "w-", lw=2, label="lands at X = 4")
        ax.set(xlabel="horizontal speed u_x", ylabel="vertical speed u_y", aspect="equal", title=title)
        ax.legend(loc="upper right")
        paths.append(save(ctx, fig, name))
    return paths


def report(ctx: Context, result) -> Section:
    """Figs. 16-20: a single state, target X = 4, Table 4, 4000 throws."""
    curve = solution_curve()
    units = result.learner.action_weights[:, :, :]  # (n_trials, 30, 2) in (u_x, u_y)
    spread = unit_spread(units, curve)
    gaps = ends(units, spread["uy_low"], spread["uy_high"])
    slopes = steepness(spread["uy_low"], spread["uy_high"])
    spans = {t: float(np.median(np.ptp(snap["action_weights"][:, :, 1], axis=1)))
             for t, snap in sorted(result.snapshots.items())}
    config = result.config
    section = Section("throw", "Figs. 16-20: throwing at a target X = 4 (Tables 3 and 4)")
    section.choices += preset_choices("table4")
    section.choices += [
        f"{counted(config.n_trials, 'trial')} of {config.n_steps} throws (the paper shows one typical trial).",
        "A unit lies on the curve when its distance to Eq. 8's curve in the velocity square is at most 0.02; "
        "the lowest, hardest throws count as avoided when the lowest unit's u_y is above the curve's lowest "
        "point (at u_x = 1) by more than 0.02.",
    ]
    section.claims += _claims(spread, gaps, slopes)
    section.notes.append(_bunching_note(spans))
    i = typical_trial(final_error(result, 400))
    section.figures.append(_trajectories_figure(ctx, trajectories(curve)))
    section.figures.append(_action_map_figure(ctx, curve, units[i], i, config.n_steps))
    section.figures += _landing_figures(ctx, curve, slopes)
    return section


throw = Experiment(groups, train, report)
