"""``somarm bench viewer``: what watching costs a training run.

Trains the same short run three ways in one process, interleaved and repeated so that
machine noise hits each alike: without a viewer, with ``LiveView`` and no browser, and with
``LiveView`` watched by a headless Chromium (when ``/usr/bin/chromium`` and Playwright are
there). Prints median wall and CPU times and their ratios to the run without a viewer,
plus the cost of one throttled ``update`` call. The view shows each run's greedy policy on its
cycle of goals, as ``somarm train --view`` does. On a machine without a GPU the browser
renders WebGL in software and competes with training for the cores: compare the CPU ratio
(the viewer's own cost inside training) with the wall ratio (everything, browser included).
"""

from __future__ import annotations

import os
import statistics
import sys
import time
import timeit

import numpy as np

from somarm.helptext import PlainHelpFormatter
from somarm.validation import OneLineParser, check_int, check_number, number, whole_number

__all__ = ["main"]

def _train_seconds(config, view) -> tuple[float, float, int]:
    """Wall seconds, CPU seconds of this process, steps done; ``view`` (or None) shows the run's greedy policy."""
    from somarm.run import RunGroup
    from somarm.viewer.live import greedy_policy

    group = RunGroup([config])
    if view is not None:
        view.set_policy(greedy_policy(group.learners[0]))
    start, cpu = time.perf_counter(), time.process_time()
    result = group.train(progress=False, on_step=None if view is None else view.update)[0]
    return time.perf_counter() - start, time.process_time() - cpu, result.steps_done


def _throttled_update_ns(view) -> float:
    observations, actions, rewards = np.zeros((1, 2)), np.zeros((1, 2)), np.zeros(1)
    view._next_time = time.perf_counter() + 3600.0  # throttled for the whole measurement
    n = 200_000
    seconds = timeit.timeit(lambda: view.update(1, observations, actions, rewards), number=n)
    view._next_time = 0.0
    return seconds / n * 1e9


def main(argv: list[str] | None = None) -> int:
    """Run the benchmark; returns 0."""
    parser = OneLineParser(prog="somarm bench viewer", description=__doc__.split("\n")[0], formatter_class=PlainHelpFormatter)
    parser.add_argument("--task", default="reach2")
    parser.add_argument("--steps", type=whole_number, default=20_000)
    parser.add_argument("--trials", type=whole_number, default=1)
    parser.add_argument("--repeats", type=whole_number, default=3)
    parser.add_argument("--rate", type=number, default=30.0, help="LiveView max_rate_hz (reward samples a second)")
    args = parser.parse_args(argv)
    for name in ("steps", "trials", "repeats"):
        check_int(f"--{name}", getattr(args, name))
    check_number("--rate", args.rate, minimum=0.0, strict_minimum=True)

    from somarm.run import RunConfig
    from somarm.viewer.live import LiveView
    from somarm.viewer.snapshot import CHROMIUM, CHROMIUM_ARGS

    config = RunConfig(task=args.task, n_steps=args.steps, n_trials=args.trials, block=100)
    _train_seconds(RunConfig(task=args.task, n_steps=200, n_trials=args.trials), None)  # compile, warm caches
    names = ("no viewer", "LiveView, no browser", "LiveView + Chromium")
    times: dict[str, list[float]] = {name: [] for name in names}
    cpu: dict[str, list[float]] = {name: [] for name in names}
    with LiveView(args.task, max_rate_hz=args.rate) as view:
        print(f"viewer at {view.url}; {args.task}, {args.trials} trial(s), {args.steps} steps, "
              f"{args.repeats} repeats, max_rate_hz={args.rate}")
        browser = page = playwright = None
        if os.path.exists(CHROMIUM):
            try:
                from playwright.sync_api import sync_playwright

                playwright = sync_playwright().start()
                browser = playwright.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
            except ImportError:
                browser = None
        for _ in range(args.repeats):
            seconds, cpu_s, steps = _train_seconds(config, None)
            times["no viewer"].append(seconds)
            cpu["no viewer"].append(cpu_s)
            sent = view.frames_sent
            seconds, cpu_s, steps = _train_seconds(config, view)
            times["LiveView, no browser"].append(seconds)
            cpu["LiveView, no browser"].append(cpu_s)
            frames_no_browser = view.frames_sent - sent
            if browser is not None:
                page = browser.new_page()
                page.goto(view.url)
                page.wait_for_function("() => typeof viewer !== 'undefined'", timeout=30_000)
                sent = view.frames_sent
                seconds, cpu_s, steps = _train_seconds(config, view)
                times["LiveView + Chromium"].append(seconds)
                cpu["LiveView + Chromium"].append(cpu_s)
                frames_browser = view.frames_sent - sent
                page.close()
        print(f"throttled update(): {_throttled_update_ns(view):.0f} ns per call")
        if browser is not None:
            browser.close()
            playwright.stop()
    base, base_cpu = statistics.median(times["no viewer"]), statistics.median(cpu["no viewer"])
    print("wall time is what the user waits; CPU time is what the training process itself spends")
    for name in names:
        if times[name]:
            wall, cpu_s = statistics.median(times[name]), statistics.median(cpu[name])
            print(f"{name:22s} wall {wall:7.3f} s ratio {wall / base:6.3f} | "
                  f"training-process CPU {cpu_s:7.3f} s ratio {cpu_s / base_cpu:6.3f}")
    print(f"frames sent in the last timed runs: {frames_no_browser} (no browser)"
          + (f", {frames_browser} (Chromium)" if browser is not None else ""))
    return 0


if __name__ == "__main__":
    from somarm.cli import main as somarm_main

    sys.exit(somarm_main(["bench", "viewer", *sys.argv[1:]]))
