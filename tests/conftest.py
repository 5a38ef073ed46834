"""Test-wide setup.

- No OpenGL (dm_control otherwise looks for a display and warns); the viewer is meshcat.
- In CI (``CI=true``) a skipped test is a failure: every part is required there (the browser
  tests need Chromium, which ``.ci/run`` installs, and the fault tests need root for a tmpfs), so
  a missing part must not turn a run green. Outside CI a skip stays a skip, with its reason.
- Ctrl-C reaches the processes the tests start, even when pytest itself was started in the
  background by a shell without job control (which starts it with SIGINT ignored, a disposition
  its children would inherit, so that the Ctrl-C tests' signals would be lost).
"""

import os
import signal
import subprocess

import pytest

os.environ.setdefault("MUJOCO_GL", "disable")
if signal.getsignal(signal.SIGINT) is signal.SIG_IGN:
    signal.signal(signal.SIGINT, signal.default_int_handler)


def in_ci() -> bool:
    """True when the ``CI`` environment variable says so (GitHub, GitLab and most others set ``true``)."""
    return os.environ.get("CI", "").strip().lower() in ("1", "true", "yes")


def _fail_if_skipped(report) -> None:
    if in_ci() and report.skipped and not hasattr(report, "wasxfail"):
        reason = report.longrepr[2] if isinstance(report.longrepr, tuple) else str(report.longrepr)
        report.outcome = "failed"
        report.longrepr = f"skipped in CI, where every part is required: {reason}"


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item, call):
    outcome = yield
    _fail_if_skipped(outcome.get_result())


@pytest.hookimpl(hookwrapper=True)
def pytest_make_collect_report(collector):
    # A module-level skip (``importorskip`` of a missing extra) is a skipped collection report.
    outcome = yield
    _fail_if_skipped(outcome.get_result())


@pytest.fixture
def small_disk(tmp_path):
    """A 1 MiB tmpfs (root only; CI requires it, see conftest.py); unmounted afterwards."""
    if os.geteuid() != 0:
        pytest.skip("a full disk is simulated with a small tmpfs, which needs root")
    mount = tmp_path / "disk"
    mount.mkdir()
    done = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=1m", "tmpfs", str(mount)], capture_output=True,
                          text=True)
    if done.returncode != 0:
        pytest.skip(f"cannot mount a tmpfs here: {done.stderr.strip()}")
    try:
        yield mount
    finally:
        subprocess.run(["umount", "-l", str(mount)], check=False)
