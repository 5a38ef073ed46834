"""Fig. 24: +NL/0.9985, -NL/0.9985 and -NL/0.9997 on throw_distance (train, measure, report)."""

from __future__ import annotations

import numpy as np

from somarm import plots
from somarm.learners.schedules import ExponentialDecay
from somarm.reproduce import metrics
from somarm.reproduce.common import Context, counted, final_error, fmt, preset_choices, run_group
from somarm.reproduce.experiment import Experiment
from somarm.reproduce.figures import legend_below, log_error_axes, save
from somarm.reproduce.report import Claim, Section
from somarm.run import RunConfig, RunResult

__all__ = ["VARIANTS", "WINDOW", "groups", "train", "crossing", "speed_up", "neighbourhood_q"]

plt = plots.pyplot()

#: The three curves of Fig. 24 and the settings that make them.
VARIANTS = {
    "+NL/0.9985": {"neighbourhood_q": True, "decay": ExponentialDecay(0.9985)},
    "-NL/0.9985": {"neighbourhood_q": False, "decay": ExponentialDecay(0.9985)},
    "-NL/0.9997": {"neighbourhood_q": False, "decay": ExponentialDecay(0.9997)},
}
#: Throws over which errors are averaged (the final error, the plotted curves, the crossings).
WINDOW = 1000


def groups(ctx: Context) -> dict[str, list[RunConfig]]:
    """The runs this experiment trains at ``ctx.seed``, by label: the three variants of Table 5 on
    throw_distance (``VARIANTS``)."""
    n_trials, n_steps = ctx.pick(20, 3), ctx.pick(25_000, 2_000)
    return {"Fig 24 +NL/-NL": [
        RunConfig(task="throw_distance", preset="table5", overrides=overrides, n_trials=n_trials,
                  n_steps=n_steps, seed=ctx.seed)
        for overrides in VARIANTS.values()
    ]}


def train(ctx: Context) -> dict[str, RunResult]:
    """The three variants of Table 5 on throw_distance (``groups``), in lockstep.

    Args:
      ctx: where and how the experiment runs (its seed, quick mode and backend).

    Returns:
      Each variant's run, by its name in ``VARIANTS``.

    Raises:
      KeyboardInterrupt: the training was stopped (see ``common.run_group``).
    """
    [(label, configs)] = groups(ctx).items()
    return dict(zip(VARIANTS, run_group(ctx, label, configs), strict=True))


def crossing(steps: np.ndarray, block: int, block_means: np.ndarray, level: float) -> float:
    """First throw at which the mean error over trials, averaged over the ``WINDOW`` throws centred on
    each block's middle, is at or below ``level`` (NaN if never).

    Args:
      steps: ``(n_blocks,)`` the step at the end of each block of ``block`` throws.
      block_means: ``(n_blocks, n_trials)`` mean reward per block.
    """
    centres = steps - block / 2  # a block's mean belongs to the middle of the block
    curve = -metrics.centred_mean(block_means.mean(axis=1), WINDOW // (2 * block))
    return metrics.steps_to_level(centres, curve, level)


def speed_up(steps: np.ndarray, block: int, fast: np.ndarray, slow: np.ndarray, level: float,
             rng: np.random.Generator) -> tuple[float, float, float]:
    """Throws ``slow`` needs to reach ``level`` over those ``fast`` needs, with its 5-95% range over
    200 bootstrap resamples of each curve's trials (``(n_blocks, n_trials)`` block means each).

    Returns:
      ``(factor, low, high)``; low and high are NaN when no resample reaches the level.
    """
    factor = crossing(steps, block, slow, level) / crossing(steps, block, fast, level)
    n = fast.shape[1]
    samples = []
    for _ in range(200):
        pick = {"fast": rng.integers(0, n, n), "slow": rng.integers(0, n, n)}
        samples.append(crossing(steps, block, slow[:, pick["slow"]], level)
                       / crossing(steps, block, fast[:, pick["fast"]], level))
    low, high = np.nanpercentile(samples, [5, 95]) if np.isfinite(samples).any() else (np.nan, np.nan)
    return factor, low, high


def _verdict(factor: float, low: float, high: float) -> bool | None:
    """Six or more, unless six lies inside the spread between samples of trials (undecided)."""
    if not np.isfinite(factor):
        return False
    if low >= 6 or high < 6:
        return bool(low >= 6)
    return None


def _claims(finals: dict[str, float], reach: dict[str, float], level: float, factor: float, low: float,
            high: float) -> list[Claim]:
    plus, slow, minus = finals["+NL/0.9985"], finals["-NL/0.9997"], finals["-NL/0.9985"]
    return [
        Claim("Fig. 24: neighbourhood Q-learning speeds convergence to near-optimal performance by a factor of at "
              "least six.",
              f"throws to reach error {fmt(level)}: +NL/0.9985 {fmt(reach['+NL/0.9985'])}, -NL/0.9997 "
              f"{fmt(reach['-NL/0.9997'])}, -NL/0.9985 {fmt(reach['-NL/0.9985'])}; "
              + (f"factor {fmt(factor, 2)} (5-95% over resampled trials: {fmt(low, 2)} to {fmt(high, 2)})."
                 if np.isfinite(factor) else "no factor, for a curve never reaches that error."),
              _verdict(factor, low, high), "factor >= 6 (undecided when 6 lies within the 5-95% range)",
              values={"factor": float(factor)}),
        Claim("Fig. 24: with the slower schedule 0.9997, -NL's final performance comes close to +NL/0.9985's.",
              f"final error -NL/0.9997 {fmt(slow)} vs +NL/0.9985 {fmt(plus)} (ratio {fmt(slow / plus, 2)}).",
              bool(slow <= 1.25 * plus), "within 25%", values={"ratio": slow / plus}),
        Claim("Fig. 24: without neighbourhood Q-learning at the same schedule, final performance is markedly worse.",
              "final error " + ", ".join(f"{k}: {fmt(v)}" for k, v in finals.items()) + ".",
              bool(minus > 1.5 * plus), "-NL/0.9985 > 1.5 x +NL/0.9985",
              values={**finals, "ratio": minus / plus}),
    ]


def _figure(ctx: Context, results: dict[str, RunResult], level: float):
    """Fig. 24: the three error curves (trailing mean over ``WINDOW`` throws), the level, the schedules."""
    steps = results["+NL/0.9985"].steps
    fig, ax = plt.subplots(figsize=(7.5, 4.5))
    for (name, r), colour in zip(results.items(), ("C0", "C3", "C2"), strict=True):
        ax.plot(steps, -plots.moving_average(r.block_means, WINDOW // r.config.block).mean(axis=1), color=colour,
                label=name)
    ax.axhline(level, color="0.5", ls="--", lw=0.8, label=f"near-optimal level {level:.3f}")
    n_trials = results["+NL/0.9985"].config.n_trials
    log_error_axes(ax, xlabel="throw", ylabel=f"error (mean over last {WINDOW} throws)",
                   title=f"Fig. 24: neighbourhood Q-learning, mean of {n_trials} trials", legend=legend_below())
    twin = ax.twinx()
    for c, colour in ((0.9985, "C0"), (0.9997, "C2")):
        twin.plot(steps, c**steps, ls=":", color=colour)
    twin.set(ylabel=r"schedules $0.9985^{throw}$, $0.9997^{throw}$ (dotted)", ylim=(0, 1.05))
    return save(ctx, fig, "fig24_neighbourhood_q.png")


def report(ctx: Context, results) -> Section:
    """Fig. 24: +NL/0.9985, -NL/0.9985 and -NL/0.9997 on throw_distance."""
    finals = {k: float(final_error(r, WINDOW).mean()) for k, r in results.items()}
    level = 1.1 * max(finals["+NL/0.9985"], finals["-NL/0.9997"])
    first = results["+NL/0.9985"]
    steps, block = first.steps, first.config.block
    reach = {k: crossing(steps, block, r.block_means, level) for k, r in results.items()}
    factor, low, high = speed_up(steps, block, first.block_means, results["-NL/0.9997"].block_means, level,
                                 np.random.default_rng(ctx.seed))
    section = Section("neighbourhood_q", "Fig. 24: neighbourhood Q-learning (throw_distance, Table 5)")
    section.choices += preset_choices("table5")
    section.choices += [
        f"{counted(first.config.n_trials, 'trial')} of {first.config.n_steps} throws per curve; error = minus "
        f"reward, plotted as the mean over the last {WINDOW} throws.",
        "Speed-up: the near-optimal level is 1.1 x the larger final error of +NL/0.9985 and -NL/0.9997 "
        f"(here {fmt(level)}); the factor is the ratio of the throws each curve needs to first reach it, "
        f"read off the mean over trials averaged over the {(2 * (WINDOW // (2 * block)) + 1) * block} throws "
        "centred on each block's middle (a trailing average would lag every crossing by half a window and pull "
        "the ratio towards 1). Its interval is the 5-95% range over 200 bootstrap resamples of the trials.",
    ]
    section.claims += _claims(finals, reach, level, factor, low, high)
    section.figures.append(_figure(ctx, results, level))
    return section


neighbourhood_q = Experiment(groups, train, report)
