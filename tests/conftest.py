"""Test-wide setup.

- No OpenGL (dm_control otherwise looks for a display and warns); the viewer is meshcat.
- In CI (``CI=true``) a skipped test is a failure: every part is required there (the browser
  tests need Chromium, which ``.ci/run`` installs, and the fault tests need root for a tmpfs), so
  a missing part must not turn a run green. Outside CI a skip stays a skip, with its reason.
"""

import os

import pytest

os.environ.setdefault("MUJOCO_GL", "disable")


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
