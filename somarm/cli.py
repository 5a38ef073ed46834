"""The ``somarm`` command line: tasks, presets, train, evaluate, compare, reproduce, bench, view, sweep."""

from __future__ import annotations

import argparse
import functools
import importlib
import os
import sys
from pathlib import Path

from somarm import __version__
from somarm.console import guard_standard_streams
from somarm.helptext import PlainHelpFormatter

# Only the standard library and these light modules load before main() runs: what a command needs
# (numpy and beyond) is imported inside main, where Ctrl-C during the import ends in one line.

__all__ = ["main"]

_BENCHMARKS = ("learner", "tasks", "viewer", "adapters", "loop")


def _out_folder(value: str | None, default: str) -> Path:
    """The ``--out`` folder: the default when the flag is absent, never when it is given empty."""
    if value is None:
        return Path(default)
    if not value.strip():
        raise ValueError("--out needs a folder name, got an empty one")
    return Path(value)


def _first_line(exc: BaseException) -> str:
    return (str(exc).strip().splitlines() or [type(exc).__name__])[-1]


def _cmd_tasks(args) -> int:
    from somarm import tasks

    for name in tasks.names():
        print(f"{name:16s} {tasks.record(name).summary}")
    print(f"{'gym:ID':16s} any Gymnasium environment with Box spaces, e.g. gym:Pendulum-v1 (multi-step episodes; "
          "--task-set passes gymnasium.make keywords)")
    from somarm.tasks.gym_envs import suite_names

    for name in suite_names():  # they run through Gymnasium's API (the gym extra)
        print(f"{name:16s} dm_control suite task (gym extra; multi-step episodes; --task-set time_limit=SECONDS, random=SEED)")
    return 0


def _cmd_presets(args) -> int:
    from somarm.learners import presets
    from somarm.learners.settings import format_settings, settings_of

    if args.name is None:
        width = max(map(len, presets.PRESETS))
        for name in presets.PRESETS:
            print(f"{name:{width}s} {presets.describe(name)}")
        return 0
    if args.name not in presets.PRESETS:
        raise ValueError(f"unknown preset {args.name!r}; allowed: {', '.join(presets.PRESETS)}")
    print(f"# {args.name}: {presets.describe(args.name)}")
    for key, text in format_settings(settings_of(presets.get(args.name))).items():
        print(f"--set {key}={text}")
    return 0


def _cmd_train(args) -> int:
    from somarm import run
    from somarm.run.claim import claim
    from somarm.run.names import run_folder

    if not args.view and (args.host is not None or args.port is not None):
        raise ValueError("--host and --port are the viewer's: give --view with them, or leave them out")
    if args.port is not None and not 0 <= args.port <= 65535:
        raise ValueError(f"--port must be in 0..65535, got {args.port}")
    args.host = "127.0.0.1" if args.host is None else args.host
    config = run.from_options(args)
    group = run.RunGroup([config])  # built once: a bad preset, --set or --task-set fails before any output
    out = _out_folder(args.out, f"runs/{run_folder(config.task, config.learner, config.seed)}")
    owner = claim(out, force=args.force)  # one writer per folder; earlier results only with --force
    try:
        return _train_into(out, group, args, owner)
    finally:
        owner.release()


def _train_into(out: Path, group, args, owner) -> int:
    """Train a built run group of one config into the claimed folder ``out``; the exit status."""
    from somarm import run
    from somarm.run.stopping import signals_deferred, sigterm_as_interrupt

    config = group.configs[0]
    sigterm_as_interrupt()
    view = None
    if args.view:
        from somarm.viewer.live import LiveView, greedy_policy

        trial_id = int(config.trial_ids_array()[0])
        about = [f"{config.learner} learner ({config.preset}), trial {trial_id}, seed {config.seed}"]
        try:
            from somarm.tasks.gym_envs import env_task

            if env_task(config.task):  # a Gymnasium MuJoCo environment or a suite task: greedy episodes on a copy
                from somarm.viewer import gym_view

                view = LiveView(env=gym_view.environment(config.task, config.task_params),
                                policy=gym_view.one_step_policy(group.task, group.learners[0], 0), host=args.host,
                                port=args.port, seed=config.seed, n_steps=config.n_steps, lines=[config.task, *about])
            else:
                view = LiveView(config.task, policy=greedy_policy(group.learners[0], 0), host=args.host,
                                port=args.port, task_params=config.task_params, seed=config.seed,
                                n_steps=config.n_steps, lines=about)
        except (OSError, RuntimeError) as exc:
            owner.release(remove_if_unused=True)  # nothing was run: leave no empty folder behind
            where = f"--host {args.host}" + ("" if args.port is None else f" --port {args.port}")
            reason = _first_line(exc).split(" did not start: ")[-1]
            raise ValueError(f"the viewer could not start on {where}: {reason}") from None
        print(f"viewer: {view.url}", flush=True)
    try:
        result = group.train(progress=not args.no_progress, on_step=None if view is None else view.update)[0]
    except BaseException:
        if view is not None:
            view.close()
        raise
    from somarm.run.folder import write_summary

    extra: dict = {}
    try:
        # A second Ctrl-C or SIGTERM waits until the run is written (it then still ends the command).
        with signals_deferred():
            if view is not None:
                view.finish(result.steps_done)  # the page says so and shows the final policy
            # The trained run first (learner, config, curves, the training's summary), so that even a SIGKILL
            # in the greedy evaluation keeps it; then the evaluation, and the summary again with it.
            kept = not (result.interrupted and owner.replacing)  # an interrupted run does not replace an earlier one
            run.write_claimed(result, owner, figures=not args.no_figures)
            if kept:
                extra = run.greedy_summary(result)  # a failed or cut evaluation is said in extra
                if "greedy_error" in extra:
                    print(f"somarm: warning: greedy evaluation failed: {extra['greedy_error']}", file=sys.stderr)
                write_summary(result, owner.folder, extra)
    except KeyboardInterrupt:
        if view is not None:
            view.close()
        print(f"interrupted after step {result.steps_done}: {_what_was_kept(result, owner, out, extra)}",
              file=sys.stderr)
        return 130
    if result.interrupted:
        if view is not None:
            view.close()
        print(f"interrupted at step {result.steps_done}: {_what_was_kept(result, owner, out, extra)}", file=sys.stderr)
        return 130
    if "greedy_mean_return" in extra:  # an episodic task: whole greedy episodes, not one step
        greedy = f"greedy mean return {extra['greedy_mean_return']:+.4f}{_cut_note(extra, config.n_trials)}"
    else:
        greedy = f"greedy mean reward {extra.get('greedy_mean_reward', float('nan')):+.4f}"
    print(f"done: {result.steps_done} steps x {config.n_trials} trial(s) in {result.wall_time:.1f} s; "
          f"{greedy}{_budget_note(config)}; results in {out}", flush=True)
    if view is not None:
        _keep_viewing(view)
    return 0


def _budget_note(config) -> str:
    """Where a run took fewer steps than its task's default run (its preset's run length, which the
    benchmarks are scored after), a note saying so: a short try-out learns less, and is not broken."""
    from somarm import tasks

    default = tasks.record(config.task).n_steps
    return f" (the task's default run is {default:,} steps)" if config.n_steps < default else ""


def _keep_viewing(view) -> None:
    """After training: the viewer keeps showing the final policy until Ctrl-C (the run is already written)."""
    import time

    if view.alive:
        print(f"training finished: the viewer keeps showing the final policy at {view.url} (Ctrl-C to stop)",
              flush=True)
    try:
        while view.serving():
            time.sleep(0.5)
    except KeyboardInterrupt:
        pass
    finally:
        view.close()


def _cut_note(summary: dict, n_trials: int) -> str:
    """`` (200 of 200 episodes cut at 1,000 steps: ...)`` where the greedy episodes' cap cut some, else ``""``."""
    cut = summary.get("greedy_episodes_cut")
    if not cut:
        return ""
    return (f" ({cut} of {summary['greedy_episodes'] * n_trials} episodes cut at {summary['greedy_episode_cap']:,} "
            "steps: --task-set evaluation_steps=N)")


def _length_note(greedy: dict) -> str:
    """What the mean episode length stands beside: where a task has a goal, a failed episode counts at the
    step limit; where it has shortest paths, their mean. ``""`` for a task with neither (a Gymnasium task)."""
    notes = []
    if "greedy_success_rate" in greedy:  # only an episode that can fail to reach a goal counts at the limit
        notes.append("a failed episode counts at the step limit")
    if "shortest_mean_episode_length" in greedy:
        notes.append(f"the shortest paths {greedy['shortest_mean_episode_length']:.2f}")
    return f" ({'; '.join(notes)})" if notes else ""


def _what_was_kept(result, owner, out: Path, extra: dict | None = None) -> str:
    if (extra or {}).get("greedy_cut"):
        return f"the trained run is written to {out} without its greedy evaluation (somarm evaluate scores it)"
    if owner.replacing:
        return f"the earlier run in {out} is kept (an interrupted run does not replace it)"
    return f"partial results written to {out}"


def _load_run(path: str):
    """``run.load`` of a run folder, or of a ``.zip`` file ``SOMQ.save`` wrote (errors name the file)."""
    from somarm import run
    from somarm.run import archive

    if not archive.is_archive(path):
        return run.load(path)
    with archive.unpacked(Path(path)) as folder:
        try:
            return run.load(folder)
        except ValueError as exc:
            raise ValueError(str(exc).replace(str(folder), str(path))) from None


def _cmd_evaluate(args) -> int:
    from somarm import run, tasks
    from somarm.run import evaluation
    from somarm.run.config import parse_assignments
    from somarm.validation import check_int, check_memory

    check_int("--observations", args.observations)
    config, learner = _load_run(args.run)
    changed = tasks.parse_params(config.task, parse_assignments(args.task_set, "--task-set"))
    seed = config.seed if args.seed is None else args.seed  # the run's own: the number summary.json has
    task = run.task_for(config, learner, changed)  # four_goals evaluates in the learned phase
    name = config.task + "".join(f" {key}={tasks.format_param(value)}" for key, value in changed.items())
    if task.episodic:  # whole greedy episodes, as summary.json has them (--observations does not apply)
        greedy = run.greedy_measures(learner, task, seed=seed)
        success = (f"success rate {greedy['greedy_success_rate']:.1%}; " if "greedy_success_rate" in greedy
                   else "")  # a Gymnasium task has no goal of its own
        print(
            f"{name}: greedy mean return {greedy['greedy_mean_return']:+.4f}{_cut_note(greedy, learner.n_trials)} (sd "
            f"{greedy['greedy_sd_return']:.4f} over {learner.n_trials} trial(s)); {success}mean episode length "
            f"{greedy['greedy_mean_episode_length']:.2f} steps{_length_note(greedy)}; "
            f"{greedy['greedy_episodes']} greedy episodes per trial, seed {seed}"
        )
        return 0
    check_memory(f"--observations {args.observations} for {learner.n_trials} trial(s)",
                 evaluation.evaluation_bytes(learner, args.observations), "give fewer --observations")
    rewards = evaluation.evaluate_greedy(learner, task, n_observations=args.observations, seed=seed)
    print(
        f"{name}: greedy mean reward {rewards.mean():+.4f} (sd {rewards.std():.4f} over "
        f"{learner.n_trials} trial(s), {args.observations} fresh observations, seed {seed})"
    )
    return 0


def _cmd_reproduce(args) -> int:
    from somarm import cluster
    from somarm.reproduce import runner
    from somarm.run.claim import claim
    from somarm.run.stopping import sigterm_as_interrupt

    if args.jobs is None:
        args.jobs = runner.default_jobs()
    # Before --out is claimed: a run that cannot fit must leave no folder and no report behind.
    cluster.check_engine(args.engine, args.ray_address)
    runner.check_request(args.only, quick=args.quick, seed=args.seed, seeds=args.seeds, jobs=args.jobs,
                         backend=args.backend)
    out = _out_folder(args.out, "reproduce")
    # An existing report is replaced only with --force (a report of --only parts is not merged
    # into an earlier one: its REPORT.md and claims.json would then mix two runs).
    owner = claim(out, force=args.force, resume=args.resume, what="a report")
    sigterm_as_interrupt()
    try:
        status = runner.reproduce(owner.path, quick=args.quick, only=args.only, progress=not args.no_progress,
                                  seeds=args.seeds, seed=args.seed, backend=args.backend, jobs=args.jobs,
                                  final_out=owner.folder, engine=args.engine, address=args.ray_address)
        owner.finish(status == 0)  # a finished report; an interrupted one only where there was none
        if status != 0 and owner.replacing:
            print(f"the earlier report in {out} is kept (an interrupted run does not replace it)", file=sys.stderr)
        return status
    except ValueError as exc:  # a file could not be written: the report so far, where there was none
        owner.finish(False)
        if owner.replacing:
            raise ValueError(f"{exc}; the new report was dropped and the earlier one in {out} is kept") from None
        raise
    except BaseException:
        owner.finish(False)
        raise
    finally:
        owner.release()


def _cmd_compare(args) -> int:
    from somarm import cluster
    from somarm.peers import compare
    from somarm.run.claim import claim
    from somarm.run.config import parse_assignments, parse_task_params
    from somarm.run.names import folder_part
    from somarm.run.stopping import sigterm_as_interrupt

    config = compare.CompareConfig(
        task=args.task,
        learners=tuple(k.strip() for k in args.learners.split(",") if k.strip()),
        samples=args.samples or compare.default_samples(args.task),
        peer_samples=args.peer_samples,
        seeds=args.seeds,
        seed=args.seed,
        observations=args.observations,
        episodes=args.episodes,
        task_params=parse_task_params(args.task, parse_assignments(args.task_set, "--task-set"), "--task-set"),
    )
    plan = compare.make_plan(config)  # checked and resolved once, before the folder is claimed
    cluster.check_engine(args.engine, args.ray_address)
    out = _out_folder(args.out, f"compare/{folder_part(config.task)}")
    owner = claim(out, force=args.force, resume=args.resume, what="a comparison")
    sigterm_as_interrupt()
    try:
        compare.compare(plan, owner.path, progress=not args.no_progress, resume=args.resume, engine=args.engine,
                        address=args.ray_address)
        owner.commit()
    except BaseException:
        owner.finish(False)
        raise
    finally:
        owner.release()
    print(f"comparison written to {out / 'compare.json'} and {out / 'compare.png'}")
    return 0


def _cmd_sweep(args) -> int:
    from somarm.sweep import cli as sweep_cli

    return sweep_cli.main(args)


def _cmd_forward(module: str, argv: list[str]) -> int:
    return int(importlib.import_module(module).main(argv) or 0)


def _engine_options(parser: argparse.ArgumentParser, units: str) -> None:
    """``--engine`` and ``--ray-address``, as ``compare`` and ``reproduce`` take them."""
    parser.add_argument("--engine", default="local", choices=("local", "ray"),
                        help=f"local (default: processes on this machine) or ray (a Ray cluster: {units})")
    parser.add_argument("--ray-address", metavar="ADDRESS",
                        help="the Ray cluster to join (HOST:PORT, as `ray start --head` prints), with --engine ray "
                             "(default: start a local one on this machine)")


def _parser(commands: list[str] | None = None) -> argparse.ArgumentParser:
    """The command line's parser; with ``commands``, only those commands get the options that need the run
    machinery imported (``train``'s and ``sweep``'s run settings), so that a listing or ``--help`` answers
    at once. None: every command complete (the docs' reference)."""

    from somarm.validation import OneLineParser, whole_number

    def complete(command: str) -> bool:
        return commands is None or command in commands

    parser = OneLineParser(prog="somarm", description="Self-organising-map reinforcement learning (Smith, 2002).",
                           epilog="`somarm COMMAND --help` describes a command and its options.",
                           formatter_class=PlainHelpFormatter)
    parser.add_argument("--version", action="version", version=f"somarm {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", title="commands", required=True,
                                parser_class=functools.partial(OneLineParser, formatter_class=PlainHelpFormatter))
    sub.add_parser("tasks", help="list the registered tasks").set_defaults(func=_cmd_tasks)
    presets_cmd = sub.add_parser("presets", help="the paper's parameter tables; with a NAME, its settings")
    presets_cmd.add_argument("name", nargs="?", help="a preset: print its settings as --set KEY=VALUE lines")
    presets_cmd.set_defaults(func=_cmd_presets)

    train = sub.add_parser("train", help="train headless and write a run folder")
    if complete("train"):
        from somarm import run

        run.add_options(train)  # every run setting, its default and help, from RunConfig
    train.add_argument("--out", help="run folder (default runs/TASK__LEARNER__seedS)")
    train.add_argument("--force", action="store_true", help="replace the run already in --out")
    train.add_argument("--no-figures", action="store_true", help="skip the PNG figures")
    train.add_argument("--no-progress", action="store_true", help="no progress bar")
    train.add_argument("--view", action="store_true", help="stream to a meshcat browser viewer")
    train.add_argument("--host", help="viewer host, with --view (default 127.0.0.1)")
    train.add_argument("--port", type=whole_number, help="viewer web port, with --view (default: a free one)")
    train.set_defaults(func=_cmd_train)

    evaluate = sub.add_parser("evaluate", help="greedy mean reward of a trained run (an episodic task's: mean return)")
    evaluate.add_argument("run", help="run folder written by `somarm train` (or a .zip file SOMQ.save wrote)")
    evaluate.add_argument("--observations", type=whole_number, default=1000,
                          help="fresh observations (1000); an episodic task runs 100 greedy episodes per trial")
    evaluate.add_argument("--seed", type=whole_number,
                          help="seed of the fresh observations (default: the run's seed, as summary.json)")
    evaluate.add_argument("--task-set", action="append", metavar="KEY=VALUE",
                          help="score the run on a changed task parameter, e.g. dynamics=actuated (the "
                               "observations and actions must keep their bounds)")
    evaluate.set_defaults(func=_cmd_evaluate)

    reproduce = sub.add_parser("reproduce", help="run every experiment of the paper and write REPORT.md")
    reproduce.add_argument("--quick", action="store_true", help="reduced trial counts (a smoke test)")
    reproduce.add_argument("--out", help="output folder (default ./reproduce)")
    reproduce.add_argument("--force", action="store_true", help="replace the report already in --out")
    reproduce.add_argument("--resume", action="store_true",
                           help="write over the report in --out in place, keeping the seeds the benchmarks "
                                "part finished there with the same settings (a long run goes on where it stopped)")
    reproduce.add_argument("--only", nargs="+", metavar="NAME", help="run only these experiments")
    reproduce.add_argument("--no-progress", action="store_true", help="no progress bars")
    reproduce.add_argument("--seeds", type=whole_number, default=1, metavar="N",
                           help="run every experiment at N seeds; verdicts say in how many they hold (1)")
    reproduce.add_argument("--seed", type=whole_number, default=0, metavar="S",
                           help="the first seed: the seeds are S .. S+N-1 (default 0)")
    reproduce.add_argument("--backend", default="mujoco", choices=("mujoco", "analytic"),
                           help="where rewards are computed: mujoco (default) or analytic (closed forms, quick)")
    reproduce.add_argument("--jobs", type=whole_number, default=None, metavar="N",
                           help="experiments run at once, each in its own process (default: the number of "
                                "cores; 1: one after another in this process, with progress bars)")
    _engine_options(reproduce, "every experiment a unit of one CPU; the comparisons' parts run here, their "
                               "learner-seed units there")
    reproduce.set_defaults(func=_cmd_reproduce)

    comp = sub.add_parser("compare", help="somarm's learners beside SB3's TD3 and SAC on one task")
    comp.add_argument("task", help="task name (see `somarm tasks`), or gym:ID for a Gymnasium environment")
    comp.add_argument("--learners", default="somq,somq+,motoric,tabular,td3,sac",
                      help="comma-separated, from somq, somq+ (the task's + preset with the interpolated response), "
                           "motoric, tabular, td3, sac (default: all six)")
    comp.add_argument("--samples", type=whole_number,
                      help="training samples of somarm's learners (default: a gym:ID's run length, the steps of its "
                           "benchmark preset; else 10000)")
    comp.add_argument("--peer-samples", type=whole_number,
                      help="training samples of td3 and sac (default: RL Baselines3 Zoo's budget for a gym:ID it "
                           "tunes, else --samples)")
    comp.add_argument("--episodes", type=whole_number, default=100,
                      help="fresh greedy episodes scored at the end, for gym:ID (a fifth at earlier rungs; default 100)")
    comp.add_argument("--seeds", type=whole_number, default=3, help="seeds S..S+K-1 for every learner (default 3)")
    comp.add_argument("--seed", type=whole_number, default=0, help="the first seed S (default 0)")
    comp.add_argument("--observations", type=whole_number, default=1000, help="fresh observations scored (1000)")
    comp.add_argument("--task-set", action="append", metavar="KEY=VALUE", help="change a task parameter")
    comp.add_argument("--out", help="output folder (default compare/TASK)")
    comp.add_argument("--force", action="store_true", help="replace an earlier comparison in --out")
    comp.add_argument("--resume", action="store_true",
                      help="go on with the comparison in --out: seeds finished there with the same settings are kept")
    comp.add_argument("--no-progress", action="store_true", help="no progress lines")
    _engine_options(comp, "every learner at every seed a unit of one CPU, its seed record written here")
    comp.set_defaults(func=_cmd_compare)

    bench = sub.add_parser("bench", help="speed and memory figures: learner, tasks, viewer, adapters, loop (pass --help after the name)")
    bench.add_argument("name", choices=_BENCHMARKS)
    sub.add_parser("view", help="meshcat browser viewer (pass --help after `view`)")

    sweep = sub.add_parser("sweep", help="search learner settings and task parameters over seeds")
    if complete("sweep"):
        from somarm import run
        from somarm.sweep import cli as sweep_cli

        run.add_options(sweep, leave_out=("trial_ids",))  # the run every point starts from; --seed is the first seed
        sweep_cli.add_options(sweep)
    sweep.set_defaults(func=_cmd_sweep)
    return parser


#: Commands whose output on stdout is their result: one that cannot be written is an error.
_OUTPUT_COMMANDS = ("tasks", "presets", "evaluate")


def _output_lost() -> bool:
    try:
        sys.stdout.flush()
    except (OSError, ValueError):
        pass
    return bool(getattr(sys.stdout, "dropped", False))


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``somarm`` console script; errors end in one line and exit code 2."""
    # The command line never renders through MuJoCo (the viewer is meshcat), so no MUJOCO_GL of the
    # environment can matter to it, and one that cannot load (osmesa not installed) must not stop it.
    os.environ["MUJOCO_GL"] = "disable"
    guard_standard_streams()  # a closed pipe or a full device on stdout/stderr never costs a run
    argv = list(sys.argv[1:] if argv is None else argv)
    try:
        # bench and view take their own options: forward everything after the name.
        if argv[:1] == ["bench"] and len(argv) > 1 and argv[1] in _BENCHMARKS:
            return _cmd_forward(f"somarm.perf.{argv[1]}", argv[2:])
        if argv[:1] == ["view"]:
            return _cmd_forward("somarm.viewer.cli", argv[1:])
        if not argv:  # `somarm` alone introduces itself: usage and the commands, on stdout
            _parser([]).print_help()
            return 0
        args = _parser(argv[:1]).parse_args(argv)  # only the command named is built whole
        status = args.func(args)
        if args.command in _OUTPUT_COMMANDS and _output_lost():  # their output is what they are for
            raise ValueError(f"cannot write the output to stdout: {sys.stdout.reason}")
        return status
    except ValueError as exc:
        print(f"somarm: error: {exc}", file=sys.stderr)
        return 2
    except MemoryError:
        print("somarm: error: out of memory (more than this machine or `ulimit -v` allows); give fewer "
              "trials, observations or seeds, or smaller maps", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("somarm: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
