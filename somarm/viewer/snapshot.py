"""Screenshots of what ``somarm view`` and ``somarm train --view`` show, taken in a headless Chromium.

    python -m somarm.viewer.snapshot reach2 --run DIR --out docs/viewer-reach2.png --at 1.0
    python -m somarm.viewer.snapshot reach2 --live --steps 20000 --out docs/viewer-train-reach2.png

Needs Debian's ``chromium`` at /usr/bin/chromium and Playwright for Python (never
``playwright install``). The page is served on 127.0.0.1 and nothing else is contacted.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from somarm.validation import number, whole_number

__all__ = ["CHROMIUM", "CHROMIUM_ARGS", "screenshot_url", "main"]

CHROMIUM = "/usr/bin/chromium"
#: WebGL without a GPU: SwiftShader through ANGLE.
CHROMIUM_ARGS = [
    "--no-sandbox", "--headless=new", "--enable-unsafe-swiftshader", "--use-gl=angle", "--use-angle=swiftshader",
    "--disable-background-networking", "--disable-component-update", "--disable-sync", "--no-first-run",
]


def _browser(playwright):
    return playwright.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)


def _check_browser() -> None:
    if not Path(CHROMIUM).exists():
        raise ValueError(f"Debian's chromium is needed at {CHROMIUM} (apt-get install chromium)")
    try:
        import playwright.sync_api  # noqa: F401
    except ImportError:
        from somarm.extras import missing

        raise missing("test", "Playwright for Python is needed (no browser download)") from None


def screenshot_url(url: str, out: str | Path, *, wait_s: float = 1.0, at_s: float | None = None,
                   size: tuple[int, int] = (900, 640), during=None) -> Path:
    """Open ``url`` in headless Chromium, let it draw, save a PNG to ``out``.

    Args:
      wait_s: seconds to let the page draw (and its animation play) before the picture.
      at_s: pause the page's animation at this time (seconds) for the picture.
      during: called with the page once it is open (to drive it: train, wait for text), before the wait.

    Raises:
      ValueError: Chromium or Playwright is missing.
    """
    _check_browser()
    from playwright.sync_api import sync_playwright

    from somarm.io import atomic_write_bytes

    with sync_playwright() as playwright:
        browser = _browser(playwright)
        try:
            page = browser.new_page(viewport={"width": size[0], "height": size[1]})
            page.goto(url, timeout=30_000)
            page.wait_for_function("() => typeof viewer !== 'undefined'", timeout=30_000)
            if during is not None:
                during(page)
            page.wait_for_timeout(int(wait_s * 1000))
            if at_s is not None:
                page.evaluate(f"() => {{ viewer.animator.pause(); viewer.animator.seek({float(at_s)}); }}")
                page.wait_for_timeout(300)
            png = page.screenshot()
        finally:
            browser.close()
    return atomic_write_bytes(Path(out), png)


def _live(args) -> Path:
    """Train ``args.task`` with the live view and take the picture once training has finished."""
    from somarm import run
    from somarm.viewer.live import LiveView, greedy_policy

    config = run.RunConfig(task=args.task, n_steps=args.steps, seed=args.seed)
    group = run.RunGroup([config])
    about = [f"{group.configs[0].learner} learner ({group.configs[0].preset}), trial 0, seed {args.seed}"]
    with LiveView(args.task, policy=greedy_policy(group.learners[0]), n_steps=args.steps, seed=args.seed,
                  lines=about) as view:

        def train(page) -> None:
            result = group.train(progress=False, on_step=view.update)[0]
            view.finish(result.steps_done)
            page.wait_for_function("() => document.getElementById('somarm-panel').innerText.includes('finished')",
                                   timeout=30_000)

        return screenshot_url(view.url, args.out, wait_s=args.wait, during=train)


def main(argv: list[str] | None = None) -> int:
    """Serve a session (as ``somarm view`` would) or a training run (``--live``), screenshot it, stop."""
    parser = argparse.ArgumentParser(prog="python -m somarm.viewer.snapshot", description=__doc__.split("\n")[0],
                                     allow_abbrev=False)
    parser.add_argument("task")
    parser.add_argument("--run", default=None)
    parser.add_argument("--out", required=True)
    parser.add_argument("--goals", type=whole_number, default=12)
    parser.add_argument("--seed", type=whole_number, default=0)
    parser.add_argument("--at", type=number, default=None, help="pause the animation at this time (seconds)")
    parser.add_argument("--wait", type=number, default=1.0, help="seconds to let the page draw (throws fly)")
    parser.add_argument("--live", action="store_true", help="train TASK with the live view and picture the end")
    parser.add_argument("--steps", type=whole_number, default=20_000, help="training steps with --live")
    args = parser.parse_args(argv)
    from somarm.viewer import sessions
    from somarm.viewer.client import MeshcatClient
    from somarm.viewer.server import MeshcatServer, stop_on_signals

    try:
        _check_browser()
        if args.live:
            print(f"wrote {_live(args)}")
            return 0
        session = sessions.load_session(args.task, run=args.run, n_goals=args.goals, seed=args.seed)
        with MeshcatServer(title=args.task) as server:
            stop_on_signals(server)
            client = MeshcatClient(server.zmq_url)
            sessions.record(session, client)
            path = screenshot_url(server.web_url, args.out, wait_s=args.wait, at_s=args.at)
            client.close()
    except ValueError as exc:
        print(f"snapshot: {exc}", file=sys.stderr)
        return 2
    print(f"wrote {path} (mean error over the goals {session.errors.mean():.4f})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
