"""Fig. 11: the twenty-link arm's greedy postures for a sweep of goals (train, measure, report)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from somarm.plots import pyplot
from somarm.reproduce import metrics
from somarm.reproduce.common import (
    Context,
    counted,
    final_error,
    fit_circle,
    fmt,
    preset_choices,
    run,
    typical_trial,
)
from somarm.reproduce.experiment import Experiment
from somarm.reproduce.figures import goal_circle, save, unit_square
from somarm.reproduce.report import Claim, Section
from somarm.run import RunConfig, RunResult, evaluation

__all__ = ["Trained", "groups", "train", "posture_distance", "measure", "reach20"]

plt = pyplot()

_N_GOALS = 100  #: goals of the sweep around the circle


@dataclass(frozen=True)
class Trained:
    """The trained run and its greedy postures for a sweep of goals around the goal circle."""

    result: RunResult
    centre: np.ndarray  #: ``(2,)`` the goal circle's centre
    radius: float  #: the goal circle's radius
    goals: np.ndarray  #: ``(100, 2)`` the sweep's goals
    postures: np.ndarray  #: ``(n_trials, 100, 20)`` the greedy joint angles for each goal
    greedy: np.ndarray  #: ``(n_trials, 100)`` the greedy fingertip distance to each goal


def groups(ctx: Context) -> dict[str, list[RunConfig]]:
    """The run this experiment trains at ``ctx.seed``, by its label: Table 1 on reach20."""
    n_trials, n_steps = ctx.pick(5, 1), ctx.pick(50_000, 3_000)
    return {"Fig 11 reach20": [RunConfig(task="reach20", preset="table1", n_trials=n_trials, n_steps=n_steps,
                                         seed=ctx.seed)]}


def train(ctx: Context) -> Trained:
    """Train Table 1 on reach20 (``groups``); the greedy postures for 100 goals evenly around the goal circle.

    Args:
      ctx: where and how the experiment runs (its seed, quick mode and backend).

    Returns:
      The run, the goal circle, the sweep and its greedy postures (``Trained``).

    Raises:
      KeyboardInterrupt: the training was stopped (see ``common.run_group``).
    """
    [(label, [config])] = groups(ctx).items()
    result = run(ctx, label, config)
    learner, task, n_trials = result.learner, result.task, result.config.n_trials
    centre, radius = fit_circle(task.sample_observations(evaluation.evaluation_rng(ctx.seed), 4000))
    angles = np.linspace(0, 2 * np.pi, _N_GOALS, endpoint=False)
    goals = centre + radius * np.column_stack([np.cos(angles), np.sin(angles)])
    postures = learner.predict(np.broadcast_to(goals, (n_trials, *goals.shape)).copy())
    greedy = -task.evaluate(np.broadcast_to(goals, (n_trials, *goals.shape)), postures)
    return Trained(result, centre, radius, goals, postures, greedy)


def posture_distance(postures: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """RMS wrapped joint-angle difference between postures ``a`` and ``b`` of ``(n_goals, n_links)``.

    Args:
      postures: ``(n_goals, n_links)`` joint angles.
      a, b: ``(n,)`` indices of the postures compared.

    Returns:
      ``(n,)`` distances in radians.
    """
    delta = postures[a] - postures[b]
    return np.sqrt((((delta + np.pi) % (2 * np.pi) - np.pi) ** 2).mean(axis=-1))


def measure(goals: np.ndarray, postures: np.ndarray, seed: int) -> dict[str, np.ndarray]:
    """Per trial ``(n_trials,)``: posture change between neighbouring goals over that between random
    goal pairs (2000 pairs drawn from ``seed``), and the Spearman correlation of goal and posture
    distance over those pairs.

    Args:
      goals: ``(n_goals, 2)`` the sweep, in order around the circle.
      postures: ``(n_trials, n_goals, n_links)`` the greedy postures.
      seed: seed of the random goal pairs.

    Returns:
      ``ratios`` and ``rhos``, each ``(n_trials,)``.
    """
    n = len(goals)
    ratios, rhos = [], []
    pairs = np.random.default_rng(seed).integers(0, n, size=(2, 2000))
    goal_d = np.linalg.norm(goals[pairs[0]] - goals[pairs[1]], axis=1)
    for p in postures:
        consecutive = posture_distance(p, np.arange(n), (np.arange(n) + 1) % n).mean()
        random_d = posture_distance(p, pairs[0], pairs[1])
        ratios.append(consecutive / random_d.mean())
        rhos.append(metrics.spearman(goal_d, random_d))
    return {"ratios": np.array(ratios), "rhos": np.array(rhos)}


def _figure(ctx: Context, trained: Trained, i: int):
    """Fig. 11: every eighth goal of the sweep and trial ``i``'s greedy posture for it."""
    from somarm.tasks import arms, kinematics

    show = np.arange(0, _N_GOALS, 8)
    joints = kinematics.joint_positions(trained.postures[i, show], arms.LINK_LENGTHS[20])
    fig, ax = plt.subplots(figsize=(5.5, 5.5))
    colours = plt.get_cmap("viridis")(np.linspace(0, 1, len(show)))
    goal_circle(ax, trained.centre, trained.radius, colour="0.6")
    for k, colour in enumerate(colours):
        ax.plot(joints[k, :, 0], joints[k, :, 1], "-o", ms=2, lw=1.2, color=colour)
        ax.plot(*trained.goals[show[k]], "x", color=colour, ms=8, mew=2)
    unit_square(ax, xlabel="x", ylabel="y", title=f"Fig. 11: greedy postures of the 20-link arm (trial {i})")
    return save(ctx, fig, "fig11_reach20_postures.png")


def report(ctx: Context, trained) -> Section:
    """Fig. 11: the 20-link arm, greedy postures for a sweep of goals."""
    m = measure(trained.goals, trained.postures, ctx.seed)
    ratio, rho = float(np.median(m["ratios"])), float(np.median(m["rhos"]))
    config = trained.result.config
    section = Section("reach20", "Fig. 11: twenty-link arm, postures for a sweep of goals (Table 1)")
    section.choices += preset_choices("table1")
    section.choices += [
        f"Table 1's parameters with a 20-D action map; {counted(config.n_trials, 'trial')} of {config.n_steps} "
        "steps.",
        "Posture distance: root-mean-square of the wrapped joint-angle differences. 'Nearby goals, similar "
        "postures' holds when neighbouring goals of a 100-goal sweep differ in posture at most a quarter as "
        "much as random goal pairs, and posture distance rises with goal distance (Spearman >= 0.5).",
    ]
    section.claims.append(
        Claim(
            "Fig. 11: nearby goals are reached with similar postures (topology preserved in a 20-D action "
            "space).",
            f"posture change between neighbouring goals / between random goal pairs: median {fmt(ratio)}; "
            f"Spearman(goal distance, posture distance) median {fmt(rho)}; greedy distance to the "
            f"sweep's goals {fmt(trained.greedy.mean())}.",
            bool(ratio <= 0.25 and rho >= 0.5),
            "ratio <= 0.25 and Spearman >= 0.5",
            values={"posture ratio": ratio, "Spearman": rho},
        )
    )
    section.figures.append(_figure(ctx, trained, typical_trial(final_error(trained.result, 1000))))
    return section


reach20 = Experiment(groups, train, report)
