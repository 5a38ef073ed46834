"""Where the time goes, and the floor MuJoCo and the learners' kernels set under the time of an experiment.

Three measurements, each in one run on this machine:

1. ``dm_env``: a throw episode of ``tasks.load`` against its MuJoCo part alone (the throw's own RK4
   steps in one native ``mj_step`` call on the launcher model, no Python per step). If the MuJoCo
   part alone is above the 100 us target, no glue can meet it.
2. ``steps``: a training step's throws of 100 and of 20 trials, as the tasks cut them, timed in the
   native rollouts alone, as a multiple of a large batch's cost per throw (the targets: 2x and 4x).
3. ``paper``: the paper's experiments one after another (lanes as usual, no worker processes), with
   the CPU seconds of every thread spent in MuJoCo's native calls and in the learners' compiled
   kernels. Their sum over the machine's 2 cores is a floor that no scheduling or glue can beat
   (the target: the whole paper in 120 s).

Usage:
  python scripts/bench_floor.py                   # all three (the paper part takes about 5 minutes)
  python scripts/bench_floor.py --skip-paper      # the first two only (about a minute)
  python scripts/bench_floor.py --quick           # reduced sizes and the --quick experiments
"""

from __future__ import annotations

import contextlib
import io
import os
import sys
import tempfile
import threading
import time
import types
from collections import defaultdict
from pathlib import Path

os.environ.setdefault("MUJOCO_GL", "disable")

import mujoco  # noqa: E402
import numpy as np  # noqa: E402

from somarm import tasks  # noqa: E402
from somarm.benchmarks import best_seconds  # noqa: E402
from somarm.learners import somq
from somarm.reproduce import common, runner  # noqa: E402
from somarm.tasks import arms, flight  # noqa: E402
from somarm.tasks.assets import model_path  # noqa: E402
from somarm.validation import OneLineParser  # noqa: E402

THROWS = ("throw", "throw_distance", "throw_wind", "throw_friction", "throw_mass")
#: The paper's experiments (what the 120 s target covers), in the paper's order.
PAPER = ("reach2", "reach20", "four_goals", "throw", "throw_maps", "neighbourhood_q", "more_inputs")


def _throws(name: str, n: int, rng: np.random.Generator) -> dict[str, np.ndarray]:
    """``n`` throws of a task: its observations' conditions and uniform launch velocities."""
    task = tasks.make(name)
    c = task.conditions(task.sample_observations(rng, n))
    out = {k: np.broadcast_to(np.asarray(c[k], dtype=np.float64), (n,)).copy() for k in ("Fr", "W", "M")}
    out["ux"], out["uy"] = rng.uniform(0.0, 1.0, (2, n))
    return out


def _plan(t: dict[str, np.ndarray], part: slice = slice(None)):
    """The tasks' own plan of these throws in one thread (steps, sorting, chunks; ``flight._plan``)."""
    return flight._plan(*(t[key][part] for key in ("ux", "uy", "Fr", "W", "M")), G=0.05,
                        tolerance=flight.DEFAULT_TOLERANCE, workers=1, chunk=flight._CHUNK)


def dm_env_floor(episodes: int, repeats: int) -> None:
    """Part 1: a dm_env throw episode against its RK4 steps in one native call."""
    print("dm_env throw episode: whole episode vs its MuJoCo steps alone (target <= 100 us)")
    model = mujoco.MjModel.from_xml_path(str(model_path("launcher")))
    model.opt.timestep = flight.SCALED_STEP
    data = mujoco.MjData(model)
    bare = flight.ProjectileBatch(1, G=0.05)  # the leanest model a throw can fly in: one body, two joints
    for name in THROWS:
        t = _throws(name, episodes, np.random.default_rng(0))
        steps = flight._model_steps(_plan(t).lengths).astype(int)  # the steps each flight takes
        env = tasks.load(name)
        actions = np.stack([t["ux"], t["uy"]], axis=-1)

        def whole(env=env, actions=actions):
            for action in actions:
                env.reset()
                env.step(action)

        def physics_only(model=model, data=data, steps=steps):
            for n in steps:
                mujoco.mj_step(model, data, nstep=int(n))

        whole_us = best_seconds(whole, repeats) / episodes * 1e6
        floor_us = best_seconds(physics_only, repeats) / episodes * 1e6
        bare_us = best_seconds(lambda: physics_only(bare.model, bare.data), repeats) / episodes * 1e6
        print(f"  {name:15s} RK4 steps a throw {steps.mean():5.1f}   episode {whole_us:5.0f} us   its MuJoCo "
              f"steps alone {floor_us:4.0f} us, in the leanest model {bare_us:4.0f} us   "
              f"{'below' if min(floor_us, bare_us) <= 100 else 'ABOVE'} the target")


def step_floor(large: int, steps: int, repeats: int) -> None:
    """Part 2: the native rollouts of 100- and 20-trial steps as multiples of a large batch."""
    print("training steps: native rollouts alone, cost per throw as a multiple of a large batch "
          "(targets <= 2x at 100 trials, <= 4x at 20)")
    for name in THROWS:
        t = _throws(name, large, np.random.default_rng(1))
        def batch(t=t):
            flight.landing_x(t["ux"], t["uy"], G=0.05, Fr=t["Fr"], W=t["W"], M=t["M"])

        big = best_seconds(batch, repeats) / large
        line = f"  {name:15s} large batch {big * 1e6:5.1f} us/throw"
        for n in (100, 20):
            plans = [_plan(t, slice(j * n, (j + 1) * n)) for j in range(steps)]

            def native(plans=plans):
                for plan in plans:
                    flight._fly(plan, 0.05)

            per_throw = best_seconds(native, repeats) / (steps * n)
            line += f"   {n}: {per_throw * 1e6:5.1f} us/throw = {per_throw / big:4.2f}x"
        print(line)


class _Clock:
    """CPU seconds of every thread inside wrapped functions, by kind."""

    def __init__(self) -> None:
        self.lock = threading.Lock()
        self.seconds: dict[str, float] = defaultdict(float)

    def wrap(self, kind: str, fn):
        def timed(*args, **kwargs):
            start = time.thread_time()
            try:
                return fn(*args, **kwargs)
            finally:
                spent = time.thread_time() - start
                with self.lock:
                    self.seconds[kind] += spent
        return timed


def _proxy(module, **wrapped) -> types.SimpleNamespace:
    """A stand-in for ``module`` whose named functions are replaced."""
    names = {n: getattr(module, n) for n in dir(module) if not n.startswith("__")}
    return types.SimpleNamespace(**{**names, **wrapped})


@contextlib.contextmanager
def _clocked():
    """A ``_Clock`` on MuJoCo's native calls and the learners' kernels, every group in this process."""
    clock = _Clock()
    saved = (flight.mj_rollout, arms.mujoco, somq._kernels, common.SPLIT_TRIAL_STEPS)
    flight.mj_rollout = _proxy(flight.mj_rollout, rollout=clock.wrap("mujoco", flight.mj_rollout.rollout))
    arms.mujoco = _proxy(mujoco, mj_kinematics=clock.wrap("mujoco", mujoco.mj_kinematics))
    somq._kernels = _proxy(somq._kernels, act_kernel=clock.wrap("kernels", somq._kernels.act_kernel),
                           learn_kernel=clock.wrap("kernels", somq._kernels.learn_kernel))
    common.SPLIT_TRIAL_STEPS = float("inf")  # no worker processes: the clock sees every group
    try:
        yield clock
    finally:
        flight.mj_rollout, arms.mujoco, somq._kernels, common.SPLIT_TRIAL_STEPS = saved


def paper_floor(quick: bool, cores: int, names: tuple[str, ...] = PAPER) -> dict[str, float]:
    """Part 3: the experiments with the CPU seconds of MuJoCo and of the learners' kernels.

    Returns:
      The totals: ``wall``, ``mujoco`` and ``kernels`` seconds, and the ``floor`` on ``cores``.
    """
    print(f"the paper's experiments{' (--quick)' if quick else ''}, one after another: wall time and the "
          "CPU seconds of all threads in MuJoCo's native calls and in the learners' kernels")
    totals = defaultdict(float)
    with _clocked() as clock, tempfile.TemporaryDirectory() as folder:
        for name in names:
            before = dict(clock.seconds)
            start = time.perf_counter()
            with contextlib.redirect_stdout(io.StringIO()):  # the runner's own lines
                runner.reproduce(Path(folder) / name, quick=quick, only=[name], progress=False)
            wall = time.perf_counter() - start
            spent = {k: clock.seconds[k] - before.get(k, 0.0) for k in ("mujoco", "kernels")}
            for key, value in (("wall", wall), *spent.items()):
                totals[key] += value
            print(f"  {name:16s} wall {wall:7.1f} s   MuJoCo {spent['mujoco']:7.1f} s   kernels "
                  f"{spent['kernels']:6.1f} s", flush=True)
    totals["floor"] = (totals["mujoco"] + totals["kernels"]) / cores
    print(f"  {'all':16s} wall {totals['wall']:7.1f} s   MuJoCo {totals['mujoco']:7.1f} s   kernels "
          f"{totals['kernels']:6.1f} s")
    print(f"  floor on {cores} cores, MuJoCo and kernels perfectly shared, nothing else: {totals['floor']:.1f} s "
          f"(target 120 s; {totals['floor'] / 120:.0%} of it)")
    return dict(totals)


def main(argv: list[str] | None = None) -> int:
    """Print the three parts; 0, or 2 after one line naming a bad option."""
    parser = OneLineParser(prog="bench_floor.py", description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="small sizes and the --quick experiments")
    parser.add_argument("--skip-paper", action="store_true", help="only the dm_env and training-step parts")
    try:
        args = parser.parse_args(argv)
    except ValueError as exc:
        print(f"bench_floor.py: error: {exc} (allowed: --quick, --skip-paper)", file=sys.stderr)
        return 2
    repeats = 1 if args.quick else 4
    dm_env_floor(episodes=50 if args.quick else 400, repeats=repeats)
    step_floor(large=6000 if args.quick else 60_000, steps=5 if args.quick else 60, repeats=repeats)
    if not args.skip_paper:
        paper_floor(args.quick, cores=os.cpu_count() or 2)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
