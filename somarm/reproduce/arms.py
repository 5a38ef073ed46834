"""The arm experiments: reach2 (Figs. 7-10), reach20 (Fig. 11), four goals (Figs. 13-15)."""

from __future__ import annotations

import numpy as np

from somarm import plots
from somarm.reproduce import metrics
from somarm.reproduce.common import (
    MOTORIC_CHOICE,
    Context,
    final_error,
    fmt,
    preset_choices,
    run,
    run_group,
    typical_trial,
)
from somarm.reproduce.report import Claim, Section
from somarm.run import RunConfig, evaluation

__all__ = ["reach2", "reach20", "four_goals"]

plt = plots.plt


def _fit_circle(points: np.ndarray) -> tuple[np.ndarray, float]:
    """Centre and radius of the goal circle, read off the task's own goal samples."""
    centre = points.mean(axis=0)
    return centre, float(np.linalg.norm(points - centre, axis=1).mean())


def _overlay_schedule(ax, steps: np.ndarray, decay, label: str) -> None:
    """f(t) on a second y axis, with one legend for both axes (so neither hides the other)."""
    twin = ax.twinx()
    twin.plot(steps, decay(steps), ls=":", color="k", label=label)
    twin.set_ylabel("annealing schedule f(t)")
    twin.set_ylim(0, 1.05)
    handles, labels = ax.get_legend_handles_labels()
    more_handles, more_labels = twin.get_legend_handles_labels()
    twin.legend(handles + more_handles, labels + more_labels, loc="center right")


def reach2(ctx: Context) -> Section:
    """Figs. 7-10: the 2-link arm reaching goals on a circle with Table 1."""
    n_trials, n_steps = ctx.pick(20, 4), ctx.pick(50_000, 3_000)
    config = RunConfig(task="reach2", preset="table1", n_trials=n_trials, n_steps=n_steps, seed=ctx.seed)
    result = run(ctx, "Figs 7-10 reach2", config)
    learner, task = result.learner, result.task
    errors = final_error(result, 1000)
    section = Section("reach2", "Figs. 7-10: two-link arm, goals on a circle (Table 1)")
    section.choices += preset_choices("table1")
    section.choices += [
        f"Run length {n_steps} steps (the paper's axis is not given); data points are means over the "
        "last 1000 steps as in Fig. 7.",
        "A trial 'fails to reach near-mean performance' when its final error (mean over the last 1000 "
        "steps) exceeds twice the median final error over trials.",
        "Topology measures: topographic error of the input map on 2000 fresh goals; for the action map, "
        "the fraction of units whose nearest unit in angle space is a map neighbour; for the Q-table, "
        "the map distance between the greedy action units of neighbouring input units.",
    ]

    fig, ax = plt.subplots(figsize=(7.5, 4.2))
    plots.learning_curve(
        ax,
        result.steps,
        result.block_means,
        window_blocks=10,
        label=f"mean of {n_trials} trials (sd error bars)",
    )
    ax.set(
        xlabel="time step t",
        ylabel="reward (mean over last 1000 steps)",
        title="Fig. 7: reach2, mean reward over trials (Table 1)",
    )
    ax.grid(alpha=0.3)
    decay = learner.config.alpha.decay
    _overlay_schedule(ax, result.steps, decay, f"f(t) = {decay}")
    section.figures.append(ctx.save(fig, "fig07_reach2_mean.png"))

    fig, ax = plt.subplots(figsize=(7.5, 4.2))
    smoothed = plots.moving_average(result.block_means, 10)
    ax.plot(result.steps, smoothed, lw=0.8)
    ax.set(
        xlabel="time step t",
        ylabel="reward (mean over last 1000 steps)",
        title=f"Fig. 8: reach2, each of the {n_trials} trials",
    )
    ax.grid(alpha=0.3)
    section.figures.append(ctx.save(fig, "fig08_reach2_trials.png"))

    median = float(np.median(errors))
    failed = int((errors > 2 * median).sum())
    allowed = max(1, round(n_trials / 20))
    section.claims.append(
        Claim(
            "Fig. 8: at most about one trial in twenty fails to reach near-mean performance.",
            f"{failed} of {n_trials} trials have a final error above twice the median "
            f"({fmt(2 * median)}); final errors {fmt(errors.min())} to {fmt(errors.max())}.",
            failed <= allowed,
            f"failures <= {allowed}",
            values={"failing trials": failed},
        )
    )

    greedy = -evaluation.evaluate_greedy(learner, task, n_observations=2000, seed=ctx.seed)
    section.claims.append(
        Claim(
            "Fig. 7: the action units come to occupy highly rewarded regions for the whole range of inputs.",
            f"greedy distance to fresh goals {fmt(greedy.mean())} (sd {fmt(greedy.std())}) over trials; "
            f"training error in the last 1000 steps {fmt(errors.mean())}.",
            bool(np.median(greedy) <= 0.05),
            "median greedy distance <= 0.05 (5% of the unit square)",
            values={"median greedy distance": float(np.median(greedy))},
        )
    )

    goals = task.sample_observations(evaluation.evaluation_rng(ctx.seed + 1), 2000)
    te, nn, jumps = [], [], []
    for i in range(n_trials):
        te.append(metrics.topographic_error(learner.input_weights[i], learner.input_grid, goals))
        nn.append(metrics.nearest_is_neighbour(learner.action_weights[i], learner.action_grid))
        jumps.append(
            metrics.greedy_jumps(learner.q[i].argmax(axis=1), learner.input_grid, learner.action_grid).mean()
        )
    te, nn, jumps = np.array(te), np.array(nn), np.array(jumps)
    n_actions = learner.q.shape[2]
    random_jump = np.abs(np.subtract.outer(np.arange(n_actions), np.arange(n_actions))).mean()
    section.claims.append(
        Claim(
            "Figs. 9-10: topology is preserved in both maps and in the Q-table (neighbouring input units "
            "choose neighbouring action units).",
            f"median over trials: input-map topographic error {fmt(np.median(te))}, action units whose nearest "
            f"unit is a map neighbour {fmt(np.median(nn))}, mean greedy jump between neighbouring input units "
            f"{fmt(np.median(jumps))} action units (random choice: {fmt(random_jump)}).",
            bool(np.median(te) <= 0.1 and np.median(nn) >= 0.9 and np.median(jumps) <= 2.0),
            "topographic error <= 0.1, nearest-is-neighbour >= 0.9, mean jump <= 2 units",
            values={"topographic error": float(np.median(te)), "nearest is neighbour": float(np.median(nn)),
                    "mean jump": float(np.median(jumps))},
        )
    )

    i = typical_trial(errors)
    centre, radius = _fit_circle(goals)
    fig, ax = plt.subplots(figsize=(5.2, 5))
    ax.add_patch(plt.Circle(centre, radius, fill=False, ls="--", color="0.5", label="goal circle"))
    plots.draw_input_map(
        ax,
        learner.input_weights[i],
        learner.q[i].argmax(axis=1),
        n_actions,
        tuple(learner.config.input_shape),
        labels=("goal x", "goal y"),
    )
    ax.set(
        xlim=(0, 1),
        ylim=(0, 1),
        aspect="equal",
        title=f"Fig. 9: input map (trial {i}), shaded by greedy action unit",
    )
    ax.legend(loc="upper right")
    section.figures.append(ctx.save(fig, "fig09_reach2_input_map.png"))

    fig, ax = plt.subplots(figsize=(5.2, 5))
    plots.draw_action_map(
        ax,
        learner.action_weights[i],
        task.action_low,
        task.action_high,
        labels=("theta1 (normalised from [-pi, pi])", "theta2 (normalised)"),
    )
    ax.set(aspect="equal", title=f"Fig. 10: action map (trial {i}), shaded by unit index")
    section.figures.append(ctx.save(fig, "fig10_reach2_action_map.png"))
    return section


def _wrapped(delta: np.ndarray) -> np.ndarray:
    return (delta + np.pi) % (2 * np.pi) - np.pi


def _posture_distance(postures: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """RMS wrapped joint-angle difference between postures ``a`` and ``b`` of ``(n_goals, n_links)``."""
    return np.sqrt((_wrapped(postures[a] - postures[b]) ** 2).mean(axis=-1))


def reach20(ctx: Context) -> Section:
    """Fig. 11: the 20-link arm, greedy postures for a sweep of goals."""
    from somarm.tasks import arms, kinematics

    n_trials, n_steps = ctx.pick(5, 1), ctx.pick(50_000, 3_000)
    config = RunConfig(task="reach20", preset="table1", n_trials=n_trials, n_steps=n_steps, seed=ctx.seed)
    result = run(ctx, "Fig 11 reach20", config)
    learner, task = result.learner, result.task
    section = Section("reach20", "Fig. 11: twenty-link arm, postures for a sweep of goals (Table 1)")
    section.choices += preset_choices("table1")
    section.choices += [
        f"Table 1's parameters with a 20-D action map; {n_trials} trials of {n_steps} steps.",
        "Posture distance: root-mean-square of the wrapped joint-angle differences. 'Nearby goals, similar "
        "postures' holds when neighbouring goals of a 100-goal sweep differ in posture at most a quarter as "
        "much as random goal pairs, and posture distance rises with goal distance (Spearman >= 0.5).",
    ]
    centre, radius = _fit_circle(task.sample_observations(evaluation.evaluation_rng(ctx.seed), 4000))
    angles = np.linspace(0, 2 * np.pi, 100, endpoint=False)
    goals = centre + radius * np.column_stack([np.cos(angles), np.sin(angles)])
    postures = learner.predict(np.broadcast_to(goals, (n_trials, *goals.shape)).copy())
    ratios, rhos = [], []
    pairs = np.random.default_rng(ctx.seed).integers(0, len(goals), size=(2, 2000))
    goal_d = np.linalg.norm(goals[pairs[0]] - goals[pairs[1]], axis=1)
    for p in postures:
        consecutive = _posture_distance(p, np.arange(100), (np.arange(100) + 1) % 100).mean()
        random_d = _posture_distance(p, pairs[0], pairs[1])
        ratios.append(consecutive / random_d.mean())
        rhos.append(metrics.spearman(goal_d, random_d))
    greedy = -task.evaluate(np.broadcast_to(goals, (n_trials, *goals.shape)), postures)
    section.claims.append(
        Claim(
            "Fig. 11: nearby goals are reached with similar postures (topology preserved in a 20-D action "
            "space).",
            "posture change between neighbouring goals / between random goal pairs: median "
            f"{fmt(np.median(ratios))}; "
            f"Spearman(goal distance, posture distance) median {fmt(np.median(rhos))}; greedy distance to the "
            f"sweep's goals {fmt(greedy.mean())}.",
            bool(np.median(ratios) <= 0.25 and np.median(rhos) >= 0.5),
            "ratio <= 0.25 and Spearman >= 0.5",
            values={"posture ratio": float(np.median(ratios)), "Spearman": float(np.median(rhos))},
        )
    )

    errors = final_error(result, 1000)
    i = typical_trial(errors)
    show = np.arange(0, 100, 8)
    lengths = arms.LINK_LENGTHS[20]
    joints = kinematics.joint_positions(postures[i, show], lengths)
    fig, ax = plt.subplots(figsize=(5.5, 5.5))
    colours = plt.get_cmap("viridis")(np.linspace(0, 1, len(show)))
    ax.add_patch(plt.Circle(centre, radius, fill=False, ls="--", color="0.6"))
    for k, colour in enumerate(colours):
        ax.plot(joints[k, :, 0], joints[k, :, 1], "-o", ms=2, lw=1.2, color=colour)
        ax.plot(*goals[show[k]], "x", color=colour, ms=8, mew=2)
    ax.set(
        xlim=(0, 1),
        ylim=(0, 1),
        aspect="equal",
        xlabel="x",
        ylabel="y",
        title=f"Fig. 11: greedy postures of the 20-link arm (trial {i})",
    )
    section.figures.append(ctx.save(fig, "fig11_reach20_postures.png"))
    return section


def four_goals(ctx: Context) -> Section:
    """Figs. 13-15: four goals by quadrant, moved mid-run; SOM-Q against the Motoric Map."""
    from somarm.tasks import four_goals as task_module

    n_trials = ctx.pick(20, 4)
    switch = ctx.pick(20_000, 1_500)
    n_steps = 2 * switch
    params = {"switch_step": switch}
    kinds = ("somq", "motoric")
    configs = [
        RunConfig(
            task="four_goals",
            learner=kind,
            preset="table2",
            n_trials=n_trials,
            n_steps=n_steps,
            seed=ctx.seed,
            task_params=params,
        )
        for kind in kinds
    ]
    runs = dict(zip(kinds, run_group(ctx, "Fig 13 four_goals", configs, snapshots_at=(switch,)), strict=True))
    section = Section("four_goals", "Figs. 13-15: four goals, moved at t = 20,000 (Table 2)")
    section.choices += preset_choices("table2")
    section.choices.append(MOTORIC_CHOICE)
    section.choices += [
        f"{n_trials} trials of {n_steps} steps, goals moved at t = {switch}; goal positions before and "
        "after the move are this project's (see the task).",
        "'Learns faster' is measured as the mean error over the first 5000 steps of each phase "
        "(first 500 in quick mode) and over the whole phase.",
    ]
    early = ctx.pick(5000, 500)
    steps = runs["somq"].steps
    phases = {"before": (steps <= early), "after": (steps > switch) & (steps <= switch + early)}
    whole = {"before": steps <= switch, "after": steps > switch}
    measured, holds, early_errors = [], True, {}
    for phase in ("before", "after"):
        e = {k: -r.block_means[phases[phase]].mean() for k, r in runs.items()}
        w = {k: -r.block_means[whole[phase]].mean() for k, r in runs.items()}
        holds &= bool(e["somq"] < e["motoric"])
        early_errors.update({f"SOM-Q {phase}": float(e["somq"]), f"Motoric Map {phase}": float(e["motoric"])})
        measured.append(
            f"{phase} the change: early error SOM-Q {fmt(e['somq'])} vs Motoric Map "
            f"{fmt(e['motoric'])} (whole phase {fmt(w['somq'])} vs {fmt(w['motoric'])})"
        )
    section.claims.append(
        Claim(
            "Fig. 13: SOM-Q learns faster than the Motoric Map both before and after the environment change.",
            "; ".join(measured) + ".",
            holds,
            "SOM-Q's early error lower in both phases",
            values=early_errors,
        )
    )

    fig, ax = plt.subplots(figsize=(7.5, 4.2))
    for colour, (name, label) in zip(
        ("C0", "C3"), (("somq", "A: SOM-Q"), ("motoric", "B: Motoric Map")), strict=True
    ):
        plots.learning_curve(
            ax, runs[name].steps, runs[name].block_means, label=label, color=colour, error_bars=False
        )
    ax.axvline(switch, color="k", ls="--", lw=0.8, label="goals move")
    ax.set(
        xlabel="time step t",
        ylabel="reward (mean over previous 100 steps)",
        title=f"Fig. 13: four goals, mean over {n_trials} trials (Table 2)",
    )
    ax.grid(alpha=0.3)
    ax.legend(loc="lower right")
    section.figures.append(ctx.save(fig, "fig13_four_goals.png"))

    somq = runs["somq"]
    snap = somq.snapshots.get(switch)
    if snap is not None:
        i = typical_trial(-somq.block_means[whole["before"]][-10:].mean(axis=0))
        n_actions = snap["q"].shape[2]
        fig, ax = plt.subplots(figsize=(5.2, 5))
        plots.draw_input_map(
            ax,
            snap["input_weights"][i],
            snap["q"][i].argmax(axis=1),
            n_actions,
            tuple(somq.learner.config.input_shape),
            labels=("input x", "input y"),
        )
        ax.axhline(0.5, color="0.4", lw=0.8)
        ax.axvline(0.5, color="0.4", lw=0.8)
        goals = np.asarray(task_module.GOALS_BEFORE)
        ax.plot(goals[:, 0], goals[:, 1], "r+", ms=12, mew=2, label="goals (before the move)")
        ax.set(
            xlim=(0, 1), ylim=(0, 1), aspect="equal", title=f"Fig. 14: input map at t = {switch} (trial {i})"
        )
        ax.legend(loc="upper right", fontsize=8)
        section.figures.append(ctx.save(fig, "fig14_four_goals_input_map.png"))
        fig, ax = plt.subplots(figsize=(5.2, 5))
        plots.draw_action_map(
            ax,
            snap["action_weights"][i],
            somq.task.action_low,
            somq.task.action_high,
            labels=("theta1 (normalised)", "theta2 (normalised)"),
        )
        ax.set(aspect="equal", title=f"Fig. 15: action map at t = {switch} (trial {i})")
        section.figures.append(ctx.save(fig, "fig15_four_goals_action_map.png"))
    return section
