"""Beyond the paper: delayed reward (gamma > 0) on reach2_obstacle, against gamma 0, a distance-greedy
policy, random moves and the shortest path of every evaluated episode."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from somarm.plots import pyplot
from somarm.reproduce.common import Context, counted, fmt, preset_choices, run_group
from somarm.reproduce.experiment import Experiment
from somarm.reproduce.figures import save
from somarm.reproduce.report import Claim, Section
from somarm.run import RunConfig, RunResult, evaluation
from somarm.tasks import obstacle, obstacle_search

__all__ = ["LABELS", "SHORTEST_FACTOR", "Trained", "groups", "train", "measure", "task_wall", "delayed_reward"]

plt = pyplot()

_EPISODES = 100  #: greedy episodes per trial, from the task's start distribution (20 when quick)
#: The two learners, in the order trained: the paper's delayed reward, and none.
LABELS = ("gamma 0.9", "gamma 0")
#: This project's target: greedy episodes with gamma 0.9 at most this many times the shortest paths' length.
SHORTEST_FACTOR = 1.3
_SHOWN = 4  #: episodes of trial 0 drawn in the figure


@dataclass(frozen=True)
class Trained:
    """Both runs, their greedy episodes, the yardsticks' episodes and the paths drawn."""

    results: list[RunResult]
    greedy: list[dict]  #: per run, ``evaluation.greedy_episodes``'s answer
    starts: np.ndarray  #: ``(n_episodes, 4)`` start angles and goals of the evaluation stream
    shortest: np.ndarray  #: ``(n_episodes,)`` the shortest path's steps from each start (search, replayed)
    random_runs: dict  #: episodes of random target changes from ``starts``
    distance_greedy: dict  #: episodes of the distance-greedy policy from ``starts``
    tips: list[list[np.ndarray]]  #: per run, trial 0's fingertip ``(n, 2)`` along its first greedy episodes


def _greedy_tips(task, learner, starts: np.ndarray) -> list[np.ndarray]:
    """The fingertip along trial 0's greedy episodes from ``starts`` ``(k, 4)``, each to the episode's end."""
    def policy(observations):
        batch = np.broadcast_to(observations, (learner.n_trials, *observations.shape)).copy()
        return np.asarray(learner.predict(batch))[0]

    episodes = task.run_episodes(policy, starts, paths=True)
    ends = 1 + episodes["length"] * task.control_steps
    return [obstacle.fingertips(episodes["path"][k, :ends[k]]) for k in range(len(starts))]


def groups(ctx: Context) -> dict[str, list[RunConfig]]:
    """The runs this experiment trains at ``ctx.seed``, by label: SOM-Q with gamma 0.9 and 0 on reach2_obstacle."""
    base = RunConfig(task="reach2_obstacle", preset="obstacle", n_trials=ctx.pick(6, 1),
                     n_steps=ctx.pick(500_000, 1_000), seed=ctx.seed, block=ctx.pick(1000, 200))
    # The contrast needs fewer trials: it fails in every one.
    contrast = dataclasses.replace(base, overrides={"gamma": 0.0}, n_trials=ctx.pick(2, 1))
    return {"reach2_obstacle gamma 0.9 / 0": [base, contrast]}


def train(ctx: Context) -> Trained:
    """SOM-Q with gamma 0.9 and 0 in lockstep (``groups``); greedy episodes of both and of the yardsticks.

    Raises:
      KeyboardInterrupt: the training was stopped (see ``common.run_group``).
    """
    [(label, configs)] = groups(ctx).items()
    results = run_group(ctx, label, configs)
    n_episodes = ctx.pick(_EPISODES, 20)
    greedy = [evaluation.greedy_episodes(r.learner, r.task, n_episodes=n_episodes, seed=ctx.seed) for r in results]
    task = results[0].task
    starts = evaluation.episode_starts(task, n_episodes, ctx.seed)
    shortest = evaluation.shortest_lengths(task, n_episodes=n_episodes, seed=ctx.seed)
    rng = np.random.default_rng(ctx.seed)
    random_runs = task.run_episodes(obstacle_search.random_policy(task, rng), starts)
    distance_greedy = task.run_episodes(obstacle_search.distance_greedy_policy(task), starts)
    tips = [_greedy_tips(task, r.learner, starts[:_SHOWN]) for r in results]
    return Trained(results, greedy, starts, shortest, random_runs, distance_greedy, tips)


def measure(trained: Trained) -> dict:
    """Success rates (mean and worst trial), mean lengths and returns of each run, and the yardsticks'.

    Returns:
      The numbers the claims read, by name (``rate``, ``worst``, ``length``, ``return``, ``beaten``: one
      per run). A length is the mean over all greedy episodes, a failed one counting at the step limit;
      ``shortest`` the mean of the shortest paths from the same starts; ``beaten`` the episodes (of all
      trials) a greedy policy finished in fewer steps than the search.
    """
    random_runs, shortest = trained.random_runs, trained.shortest
    return {
        "rate": [float(g["success_rate"].mean()) for g in trained.greedy],
        "worst": [float(g["success_rate"].min()) for g in trained.greedy],
        "length": [float(g["mean_length"].mean()) for g in trained.greedy],
        "return": [float(g["mean_return"].mean()) for g in trained.greedy],
        "beaten": [int((g["success"] & (g["lengths"] < shortest)).sum()) for g in trained.greedy],
        "shortest": float(shortest.mean()),
        "random_rate": float(random_runs["success"].mean()),
        "distance_rate": float(trained.distance_greedy["success"].mean()),
        "distance_length": float(trained.distance_greedy["length"].mean()),
    }


def _claims(m: dict, n_trials: int, n_episodes: int) -> list[Claim]:
    rate, length, best = m["rate"], m["length"], m["shortest"]
    ratio = length[0] / best
    return [
        Claim("Delayed reward: SOM-Q with gamma 0.9 learns to go around the wall to goals behind it (this "
              "project's target, not the paper's).",
              f"gamma 0.9: {fmt(100 * rate[0], 3)}% of {n_trials} x {n_episodes} greedy episodes reach the goal "
              f"(worst trial {fmt(100 * m['worst'][0], 3)}%); mean return {fmt(m['return'][0], 3)} "
              f"(gamma 0: {fmt(m['return'][1], 3)}).",
              rate[0] >= 0.9, ">= 90% of greedy episodes from the task's start distribution reach the goal",
              values={"success gamma 0.9": rate[0], "worst trial": m["worst"][0]}),
        Claim("Greedy episodes with gamma 0.9 are close to the shortest path.",
              f"mean {fmt(length[0], 3)} steps over all greedy episodes (a failed one counting at the step limit) "
              f"against {fmt(best, 3)} for the shortest paths from the same starts: {fmt(ratio, 3)}x; "
              f"{m['beaten'][0]} of {n_trials * n_episodes} greedy episodes were shorter than the search's path.",
              bool(np.isfinite(ratio) and ratio <= SHORTEST_FACTOR),
              f"mean length <= {SHORTEST_FACTOR:g} x the shortest paths' mean",
              values={"mean length": length[0], "shortest": best, "ratio": ratio}),
        Claim("Without delayed reward (gamma 0), and for a policy that takes the nearest next step, the goal "
              "behind the wall is reached clearly less often.",
              f"success gamma 0: {fmt(100 * rate[1], 3)}% (mean length {fmt(length[1], 3)}); the distance-greedy "
              f"policy: {fmt(100 * m['distance_rate'], 3)}% (mean length {fmt(m['distance_length'], 3)}); random "
              f"target changes: {fmt(100 * m['random_rate'], 3)}%; gamma 0.9: {fmt(100 * rate[0], 3)}%.",
              max(rate[1], m["distance_rate"]) <= rate[0] - 0.5,
              "gamma 0 and the distance-greedy policy at least 50 points below gamma 0.9",
              values={"success gamma 0": rate[1], "success distance-greedy": m["distance_rate"]}),
        Claim("A goal that a straight move reaches is rare: the distance-greedy policy, which moves the "
              "fingertip straight at the goal where nothing is in the way, reaches at most 10% of them.",
              f"{fmt(100 * m['distance_rate'], 3)}% of {n_episodes} episodes from the task's start distribution.",
              m["distance_rate"] <= 0.1, "distance-greedy success <= 10%",
              values={"success distance-greedy": m["distance_rate"]}),
    ]


def task_wall() -> tuple[tuple[float, float], tuple[float, float]]:
    """The wall's lower-left corner and (width, height) in the plane, read from the model."""
    import mujoco

    from somarm.tasks.assets import model_path

    model = mujoco.MjModel.from_xml_path(str(model_path("arm2_obstacle")))
    pos, size = model.geom("wall").pos, model.geom("wall").size
    return (float(pos[0] - size[0]), float(pos[1] - size[1])), (float(2 * size[0]), float(2 * size[1]))


def _figure(ctx: Context, trained: Trained):
    """Learning curves of both runs (left); trial 0's greedy fingertip paths around the wall (right)."""
    fig, (curves, paths) = plt.subplots(1, 2, figsize=(12, 4.8))
    for result, label in zip(trained.results, LABELS, strict=True):
        means = result.block_means
        curves.plot(result.steps, means.mean(axis=1), label=label)
        curves.fill_between(result.steps, means.min(axis=1), means.max(axis=1), alpha=0.2)
    curves.set(xlabel="training step (one control interval in every trial)",
               ylabel="mean reward per step (-(1 + distance))", title="Learning: mean reward of the exploring policy")
    curves.legend()
    wall = task_wall()
    paths.add_patch(plt.Rectangle(wall[0], *wall[1], color="0.35", label="wall"))
    x0, x1, y0, y1 = obstacle.GOAL_REGION
    for left in (x0, 2 * obstacle.WALL_X - x1):
        paths.add_patch(plt.Rectangle((left, y0), x1 - x0, y1 - y0, fill=False, ls=":", color="green"))
    for k in range(len(trained.tips[0])):
        start, goal = trained.starts[k, :2], trained.starts[k, 2:]
        for tips, label, colour in zip([t[k] for t in trained.tips], LABELS, ("C0", "C1"), strict=True):
            paths.plot(tips[:, 0], tips[:, 1], color=colour, lw=1, label=f"{label}: fingertip" if k == 0 else None)
        paths.plot(*obstacle.fingertips(start), "ks", ms=4, label="starts" if k == 0 else None)
        paths.plot(*goal, "o", color="green", ms=6, label="goals (dotted: their regions)" if k == 0 else None)
    paths.set(aspect="equal", xlim=(0.0, 1.0), ylim=(0.1, 0.85),
              title=f"Trial 0's greedy episodes from the first {len(trained.tips[0])} starts")
    paths.legend(fontsize=7, loc="lower left")
    fig.tight_layout()
    return save(ctx, fig, "delayed_reward.png", crop=False)


def report(ctx: Context, trained) -> Section:
    """SOM-Q with gamma 0.9 and 0 on reach2_obstacle; greedy success and length; yardsticks."""
    config = trained.results[0].config
    params = trained.results[0].task.params
    notes = [
        "The task: the actuated two-link arm starts at rest on one side of a wall (a pose within "
        f"+-{params.start_spread:g} rad of a rest pose, or its mirror image), and the goal lies behind the wall, "
        "on the other side; the observation is the joint angles and the goal (x, y). Each step moves the joint "
        f"targets by at most {params.max_step:g} rad, the servos track them for {params.control_interval:g} s with "
        "MuJoCo contacts, and the reward is -(1 + d), d the fingertip's distance to the goal.",
        "The shortest path of every evaluated episode: a beam search (8 nodes per depth) over a 7 x 7 grid of "
        "the action box, without merging states, guided by the joint-space distance around the wall, the last "
        "move of the nodes that end near the goal refined over the continuous box; each path found is replayed "
        "through the task's own episodes, and its length is the replay's.",
        f"Both learners trained in lockstep, {counted(config.n_trials, 'trial')} with gamma 0.9 and "
        f"{counted(trained.results[1].config.n_trials, 'trial')} with gamma 0, {config.n_steps:,} steps each; "
        f"episodes that end (goal, or {params.step_limit} steps) restart in their own trial at the next step.",
    ]
    claims = _claims(measure(trained), config.n_trials, len(trained.starts))
    return Section(
        "delayed_reward",
        "Beyond the paper: delayed reward around a wall (reach2_obstacle)",
        figures=[_figure(ctx, trained)],
        claims=claims,
        notes=notes,
        choices=preset_choices("obstacle"),
    )


delayed_reward = Experiment(groups, train, report)
