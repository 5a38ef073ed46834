"""Screenshots of what ``somarm view`` shows, taken in a headless Chromium (for docs and reports).

    python -m somarm.viewer.snapshot reach2 --run DIR --out docs/viewer-reach2.png

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


def screenshot_url(url: str, out: str | Path, *, wait_s: float = 1.0, size: tuple[int, int] = (900, 640)) -> Path:
    """Open ``url`` in headless Chromium, let it draw for ``wait_s``, save a PNG to ``out``.

    Raises:
      ValueError: Chromium or Playwright is missing, or the page has no meshcat viewer.
    """
    if not Path(CHROMIUM).exists():
        raise ValueError(f"Debian's chromium is needed at {CHROMIUM} (apt-get install chromium)")
    try:
        from playwright.sync_api import sync_playwright
    except ImportError:
        raise ValueError("Playwright for Python is needed (pip install playwright; no browser download)") from None
    out = Path(out)
    with sync_playwright() as playwright:
        browser = playwright.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
        try:
            page = browser.new_page(viewport={"width": size[0], "height": size[1]})
            page.goto(url, timeout=30_000)
            page.wait_for_function("() => typeof viewer !== 'undefined'", timeout=30_000)
            page.wait_for_timeout(int(wait_s * 1000))
            png = page.screenshot()
        finally:
            browser.close()
    from somarm.io import atomic_write_bytes

    return atomic_write_bytes(out, png)


def main(argv: list[str] | None = None) -> int:
    """Serve a session (as ``somarm view`` would), screenshot it, stop the server."""
    parser = argparse.ArgumentParser(prog="python -m somarm.viewer.snapshot", description=__doc__.split("\n")[0],
                                     allow_abbrev=False)
    parser.add_argument("task")
    parser.add_argument("--run", default=None)
    parser.add_argument("--out", required=True)
    parser.add_argument("--goals", type=whole_number, default=12)
    parser.add_argument("--seed", type=whole_number, default=0)
    parser.add_argument("--goal", type=whole_number, default=0, help="which goal of the cycle to show (arm tasks)")
    parser.add_argument("--wait", type=number, default=1.0, help="seconds to let the page draw (throws fly)")
    args = parser.parse_args(argv)
    from somarm.viewer import sessions, shows
    from somarm.viewer.client import MeshcatClient
    from somarm.viewer.server import MeshcatServer, stop_on_signals

    try:
        session = sessions.load_session(args.task, run=args.run, n_goals=args.goals, seed=args.seed)
        with MeshcatServer() as server:
            stop_on_signals(server)
            client = MeshcatClient(server.zmq_url)
            if isinstance(session.show, shows.ArmShow):
                k = args.goal % len(session.observations)
                client.send_batch(session.show.setup())
                client.send_batch(session.show.frame(session.observations[k], session.actions[k]))
                print(f"goal {session.observations[k]} error {session.errors[k]:.4f}")
            else:
                sessions.record(session, client)
            path = screenshot_url(server.web_url, args.out, wait_s=args.wait)
            client.close()
    except ValueError as exc:
        print(f"snapshot: {exc}", file=sys.stderr)
        return 2
    print(f"wrote {path} (mean error over the goals {session.errors.mean():.4f})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
