"""``somarm view TASK``: watch a learner (trained or not) act on a task in the browser, or export it.

Examples:

    somarm view reach2 --run runs/reach2__somq__seed0     # live, until Ctrl-C
    somarm view throw --run runs/throw__somq__seed0        # the fan of Fig. 17, animated
    somarm view reach20 --run DIR --goals 9                # Fig. 11: nine postures at once
    somarm view reach2 --html reach2.html                  # offline page, no server
    somarm view reach2 --task-set dynamics=actuated --run DIR   # the servos move the arm, animated
    somarm view reach2_obstacle --run DIR                  # greedy episodes around the wall
    somarm view gym:Reacher-v5 --run DIR --goals 5         # 5 greedy episodes of a Gymnasium MuJoCo task
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from somarm.helptext import RawPlainHelpFormatter
from somarm.validation import OneLineParser, number, whole_number

__all__ = ["main", "build_parser"]


#: At most this many goals: each is a pose in the page (1000 made a 28 MB HTML file).
MAX_GOALS = 200


def build_parser() -> argparse.ArgumentParser:
    """The ``somarm view`` argument parser."""
    parser = OneLineParser(prog="somarm view", description=__doc__.split("\n")[0],
                           formatter_class=RawPlainHelpFormatter, epilog="\n".join(__doc__.split("\n")[2:]))
    parser.add_argument("task", help="task name (reach2, four_goals, reach20, throw, throw_distance, ...), or gym:ID "
                                     "of a Gymnasium MuJoCo environment")
    parser.add_argument("--run", default=None, help="run folder (config.json + learner.npz); default: untrained")
    parser.add_argument("--host", default="127.0.0.1",
                        help="address the page listens on (default 127.0.0.1: this machine only)")
    parser.add_argument("--port", type=whole_number, default=None, help="web port (default: a free one)")
    parser.add_argument("--html", default=None, metavar="FILE",
                        help="write a self-contained HTML animation to FILE instead of serving")
    parser.add_argument("--seed", type=whole_number, default=0, help="seed of the goals shown (default 0)")
    parser.add_argument("--goals", type=whole_number, default=12,
                        help=f"how many goals to cycle through (default 12, at most {MAX_GOALS}); for gym:ID, "
                             "episodes (at most 3,000 states in all)")
    parser.add_argument("--trial", type=whole_number, default=None,
                        help="which trial of the run to show, by its trial id (default: the run's first)")
    parser.add_argument("--interval", type=number, default=1.5, help="seconds per goal when live (default 1.5)")
    parser.add_argument("--once", action="store_true", help="go through the goals once, then stop")
    parser.add_argument("--task-set", action="append", default=None, metavar="KEY=VALUE",
                        help="change a task parameter over the run's (repeatable), e.g. dynamics=actuated")
    return parser


def main(argv: list[str] | None = None) -> int:
    """Run ``somarm view``; returns the exit status (0 ok, 2 bad input, 130 Ctrl-C)."""
    try:
        args = build_parser().parse_args(argv)
        from somarm import tasks
        from somarm.validation import check_int, check_number
        from somarm.viewer import sessions

        tasks.record(args.task)  # an unknown task is named before anything else is checked
        check_int("--goals", args.goals)
        if args.goals > MAX_GOALS:
            raise ValueError(f"--goals must be at most {MAX_GOALS}, got {args.goals}")
        check_int("--seed", args.seed, minimum=0)
        if args.trial is not None:
            check_int("--trial", args.trial, minimum=0)
        check_number("--interval", args.interval, minimum=0.0)
        if args.port is not None and not 0 <= args.port <= 65535:
            raise ValueError(f"--port must be in 0..65535, got {args.port}")
        if args.html is not None and (not args.html or Path(args.html).is_dir()):
            raise ValueError(f"--html takes a file name, got {'a folder, ' if args.html else ''}{args.html!r}")
        from somarm.run.config import parse_assignments

        task_set = tasks.parse_params(args.task, parse_assignments(args.task_set, "--task-set"))
        from somarm.tasks.gym_envs import env_task

        if env_task(args.task):  # a Gymnasium MuJoCo environment or a suite task: its own model, greedy episodes
            return _view_gym(args, task_set)
        session = sessions.load_session(args.task, run=args.run, n_goals=args.goals, seed=args.seed,
                                        trial=args.trial, task_set=task_set)
        if args.html is not None:
            from somarm.viewer.client import Recorder
            from somarm.viewer.html import write_html

            recorder = Recorder()
            sessions.record(session, recorder)
            path = write_html(args.html, recorder.commands(), title=args.task)
            print(f"wrote {path} (mean error {session.errors.mean():.4f} over {len(session.errors)} goals)")
            return 0
    except ValueError as exc:
        print(f"somarm: error: {exc}", file=sys.stderr)
        return 2
    return _serve(session, args)


def _view_gym(args, task_set) -> int:
    """``somarm view gym:ID`` (or ``dmc:DOMAIN-TASK``): ``--goals`` episodes of the run's greedy policy (or random actions)."""
    from somarm.viewer import gym_view

    try:
        written = gym_view.view(args.task, run=args.run, trial=args.trial, task_set=task_set, episodes=args.goals,
                                seed=args.seed, html=args.html, host=args.host, port=args.port,
                                log=lambda line: print(line, flush=True))
    except (RuntimeError, OSError) as exc:
        where = f"--host {args.host}" + ("" if args.port is None else f" --port {args.port}")
        raise ValueError(f"the viewer could not start on {where}: {str(exc).split(' did not start: ')[-1]}") from None
    except KeyboardInterrupt:
        return 130
    print(f"wrote {written}")
    return 0


def _serve(session, args) -> int:
    from somarm.viewer import sessions
    from somarm.viewer.client import MeshcatClient
    from somarm.viewer.server import MeshcatServer, stop_on_signals

    server = MeshcatServer(host=args.host, port=args.port, title=args.task)
    try:
        server.start()
    except (RuntimeError, OSError) as exc:
        where = f"--host {args.host}" + ("" if args.port is None else f" --port {args.port}")
        reason = str(exc).split(" did not start: ")[-1]
        print(f"somarm: error: the viewer could not start on {where}: {reason}", file=sys.stderr)
        return 2
    stop_on_signals(server)
    client = MeshcatClient(server.zmq_url)
    try:
        print(f"meshcat viewer for {args.task}: open {server.web_url}  (Ctrl-C to stop)", flush=True)
        sessions.play(session, client, interval_s=args.interval, once=args.once,
                      log=lambda line: print(line, flush=True))
        return 0
    except KeyboardInterrupt:
        return 130
    finally:
        client.close()
        server.stop()


if __name__ == "__main__":
    sys.exit(main())
