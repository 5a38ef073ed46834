"""``somarm bench tasks``: evaluations per second of every task, MuJoCo beside the closed forms.

For every registered task the same observations and actions (uniform in the task's bounds)
are evaluated in one batched call through MuJoCo (the default backend) and through the
analytic backend, in the same run, so their ratio is meaningful on a busy machine. Beside them:
the largest difference between the two (the landing error for the throws, the fingertip
error for the arms), the cost of one dm_env episode (``tasks.load``), and the cost of one
training step of 100 trials (``reset`` + ``step``), which is what an experiment pays.
Each rate is the best of ``--repeats`` runs. ``--threads 1`` gives the one-core figures, whose ratio
to the default two threads shows how much of the machine the run actually got.
"""

from __future__ import annotations

import time

import numpy as np

from somarm import tasks
from somarm.tasks import flight
from somarm.tasks import throw as throw_module
from somarm.validation import OneLineParser, check_int

__all__ = ["TARGETS", "measure", "main"]

#: The issue's targets for batched MuJoCo evaluations per second on this 2-core machine.
TARGETS: dict[str, float] = {"reach2": 1e6, "reach20": 3e5, "throw": 5e4, "throw_distance": 5e4,
                             "throw_wind": 5e4, "throw_friction": 5e4, "throw_mass": 5e4}
_SIZES = {"reach2": 400_000, "reach20": 100_000, "four_goals": 400_000}
_THROWS = 60_000


def _best_rate(fn, n: int, repeats: int) -> float:
    """Best evaluations per wall-clock second.

    Wall-clock, not CPU time: in this sandbox the process CPU clocks count the main thread only.
    """
    best = float("inf")
    for _ in range(repeats):
        start = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - start)
    return n / best


def _difference(name: str, task, observations: np.ndarray, actions: np.ndarray) -> float:
    """Largest |MuJoCo - analytic| of the physical outcome: landing x, or fingertip position."""
    if name.startswith("throw"):
        c = task.conditions(observations)
        kwargs = {"params": task.params, "Fr": c["Fr"], "W": c["W"], "M": c["M"]}
        mj = throw_module.landing_x(actions[:, 0], actions[:, 1], backend="mujoco", **kwargs)
        an = throw_module.landing_x(actions[:, 0], actions[:, 1], backend="analytic", **kwargs)
        return float(np.abs(mj - an).max())
    from somarm import kinematics
    from somarm.tasks import arms

    n_links = actions.shape[1]
    return float(np.abs(arms.fingertips(actions, n_links) - kinematics.forward(actions, arms.LINK_LENGTHS[n_links])).max())


def measure(name: str, *, n: int, repeats: int, episodes: int, steps: int) -> dict[str, float]:
    """Figures of one task: rates of both backends, their difference, dm_env and 100-trial costs."""
    rng = np.random.default_rng(0)
    mujoco_task = tasks.make(name)
    analytic_task = tasks.make(name, backend="analytic")
    observations = mujoco_task.sample_observations(rng, n)
    actions = rng.uniform(mujoco_task.action_low, mujoco_task.action_high, (n, mujoco_task.action_low.size))
    warm = slice(0, min(n, 2000))
    mujoco_task.evaluate(observations[warm], actions[warm])  # build the batch models outside the timing
    figures = {
        "mujoco": _best_rate(lambda: mujoco_task.evaluate(observations, actions), n, repeats),
        "analytic": _best_rate(lambda: analytic_task.evaluate(observations, actions), n, repeats),
        "difference": _difference(name, mujoco_task, observations, actions),
    }
    env = tasks.load(name)
    env_actions = actions[:episodes]
    start = time.perf_counter()
    for action in env_actions:
        env.reset()
        env.step(action)
    figures["dm_env_us"] = (time.perf_counter() - start) / len(env_actions) * 1e6
    batch = tasks.make(name, n_trials=100)
    trial_actions = rng.uniform(batch.action_low, batch.action_high, (steps, 100, batch.action_low.size))
    batch.reset()
    batch.step(trial_actions[0])  # this thread's batch model is built here, outside the timing
    start = time.perf_counter()
    for a in trial_actions:
        batch.reset()
        batch.step(a)
    figures["step100_ms"] = (time.perf_counter() - start) / steps * 1e3
    return figures


def main(argv: list[str] | None = None) -> int:
    """Print the table; returns 0 (a benchmark reports, it does not fail)."""
    parser = OneLineParser(prog="somarm bench tasks", description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="small batches, one repeat (a smoke run)")
    parser.add_argument("--repeats", type=int, default=3, help="timed runs per figure, best kept (3)")
    parser.add_argument("--only", nargs="+", metavar="TASK",
                        help="benchmark only these tasks ('driven': the actuated and obstacle rows)")
    parser.add_argument("--threads", type=int, default=2, help="threads of the MuJoCo backend (2)")
    args = parser.parse_args(argv)
    check_int("--repeats", args.repeats)
    tasks.set_threads(check_int("--threads", args.threads))
    names = args.only or [name for name in tasks.names() if name != "reach2_obstacle"]
    driven = args.only is None or "driven" in names or "reach2_obstacle" in names
    names = [name for name in names if name not in ("driven", "reach2_obstacle")]
    for name in names:
        tasks.describe(name)  # unknown names fail here, in one line
    scale = 20 if args.quick else 1
    repeats = 1 if args.quick else max(1, args.repeats)
    episodes, steps = (30, 5) if args.quick else (300, 40)
    print(f"{'task':15s} {'MuJoCo/s':>11s} {'analytic/s':>11s} {'ratio':>7s} {'|MJ-exact|':>10s} "
          f"{'dm_env us':>9s} {'100-trial step ms':>17s}  target")
    for name in names:
        n = max(1000, (_SIZES.get(name, _THROWS)) // scale)
        f = measure(name, n=n, repeats=repeats, episodes=episodes, steps=steps)
        target = TARGETS.get(name)
        verdict = ""
        if target is not None:
            verdict = f">= {target:.0e}/s: {'met' if f['mujoco'] >= target else 'MISSED'}"
            if name.startswith("throw"):
                verdict += f"; error <= 1e-6: {'met' if f['difference'] <= 1e-6 else 'MISSED'}"
        print(f"{name:15s} {f['mujoco']:11.3g} {f['analytic']:11.3g} {f['analytic'] / f['mujoco']:7.0f} "
              f"{f['difference']:10.1e} {f['dm_env_us']:9.0f} {f['step100_ms']:17.2f}  {verdict}", flush=True)
    print("MuJoCo/s and analytic/s: evaluations per second in one batched call, same inputs; "
          "|MJ-exact|: largest landing (throws) or fingertip (arms) difference.")
    print(f"Throws: RK4 step per throw from {flight.STEP_LADDER} for a landing-error bound of "
          f"{flight.DEFAULT_TOLERANCE:g}; {flight.THREADS} thread(s); batches sorted by step and u_y.")
    if driven:
        from somarm.benchmarks import driven as driven_rows

        driven_rows.print_rows(quick=args.quick, repeats=repeats)
    return 0
