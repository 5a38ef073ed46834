"""``somarm reproduce --jobs``: the parent's status (a bar on a terminal, plain lines elsewhere) and its estimates."""

from __future__ import annotations

import fcntl
import io
import os
import pty
import re
import struct
import subprocess
import sys
import termios
import time

from somarm import status as status_module
from somarm.reproduce.parallel import expected_durations
from somarm.status import Status, time_left

_ENV = {**os.environ, "MUJOCO_GL": "disable"}


class _Clock:
    def __init__(self) -> None:
        self.now = 1000.0

    def __call__(self) -> float:
        return self.now


def test_the_time_left_places_the_waiting_experiments_on_the_first_free_worker():
    # Workers free after 10 s and 2 s: the first waiting one (5 s) goes to the second (ends at 7), the
    # next (5 s) to the same worker again (ends at 12), the last (1 s) to the first one free then (at 10).
    assert time_left([10.0, 2.0], [5.0, 5.0, 1.0], workers=2) == 12.0
    assert time_left([], [4.0, 3.0, 3.0], workers=3) == 4.0  # every worker idle
    assert time_left([3.0], [], workers=2) == 3.0


def test_the_fractions_and_time_left_follow_the_pace_the_finished_experiments_set(monkeypatch):
    clock = _Clock()
    monkeypatch.setattr(status_module.time, "monotonic", clock)
    log = io.StringIO()
    show = Status(["a", "b", "c"], workers=2, expected={"a": 10.0, "b": 20.0, "c": 10.0}, stream=log)
    show.started("a", "in process 11")
    show.started("b", "in process 12")
    clock.now += 5
    assert show.fractions() == {"a": 0.5, "b": 0.25} and show.seconds_left() == 15.0  # b: 15 s, c after a: 5 + 10
    clock.now += 15  # a took twice its expected time: everything is expected to take twice as long
    show.finished("a")
    assert show.pace() == 2.0
    assert show.fractions() == {"b": 0.5}
    show.started("c", "in process 11")
    assert show.seconds_left() == 20.0  # b: 40 - 20, c: 20
    clock.now += 100  # past every estimate: a fraction stays below 1 while it runs
    assert max(show.fractions().values()) == 0.99


def test_away_from_a_terminal_the_events_are_lines_and_the_status_a_line_a_minute(monkeypatch):
    clock = _Clock()
    monkeypatch.setattr(status_module.time, "monotonic", clock)
    log = io.StringIO()
    show = Status(["a", "b"], workers=2, expected={"a": 60.0}, stream=log)
    show.started("a", "in process 11")
    show.progress("a", "Fig. 7", 300, 1000)
    for _ in range(10):  # many redraws within the minute: none is written
        clock.now += 5
        show.draw()
    assert log.getvalue() == "a: started in process 11\n"
    clock.now += 15
    show.draw()
    lines = log.getvalue().splitlines()
    assert "\r" not in log.getvalue() and len(lines) == 2
    # b has no measured duration: the time left is said to be unknown, not made up.
    assert re.fullmatch(r"0/2 done, 1 running: a ~\d+% \(Fig\. 7 300/1000\) \| 1:05, time left unknown.*", lines[1])


def test_the_expected_durations_cover_every_default_experiment_and_scale_with_the_seeds():
    from somarm.reproduce.runner import EXPERIMENTS

    for quick in (False, True):
        one, three = expected_durations(quick, 1), expected_durations(quick, 3)
        assert set(EXPERIMENTS) <= set(one)
        assert all(s > 0 and three[name] == 3 * s for name, s in one.items())


def _in_a_terminal(argv: list[str], *, columns: int = 120, timeout: float = 300) -> tuple[int, str]:
    """Run ``argv`` with stdin, stdout and stderr on a pseudo-terminal ``columns`` wide; its exit code and output."""
    master, slave = pty.openpty()
    fcntl.ioctl(slave, termios.TIOCSWINSZ, struct.pack("HHHH", 24, columns, 0, 0))
    proc = subprocess.Popen(argv, stdin=slave, stdout=slave, stderr=slave, env=_ENV, close_fds=True)
    os.close(slave)
    chunks, deadline = [], time.monotonic() + timeout
    try:
        while time.monotonic() < deadline:
            try:
                chunk = os.read(master, 65536)
            except OSError:  # the other end closed: the process has ended
                break
            if not chunk:
                break
            chunks.append(chunk)
        return proc.wait(timeout=max(1.0, deadline - time.monotonic())), b"".join(chunks).decode(errors="replace")
    finally:
        proc.kill()
        os.close(master)


def _reproduce(out) -> list[str]:
    return [sys.executable, "-m", "somarm.cli", "reproduce", "--quick", "--backend", "analytic", "--jobs", "2",
            "--only", "reach2", "throw", "--out", str(out)]


def test_on_a_terminal_one_bar_is_redrawn_in_place_with_the_events_above_it(tmp_path):
    code, out = _in_a_terminal(_reproduce(tmp_path / "tty"), columns=100)
    assert code == 0, out
    redraws = [part for line in out.split("\n") for part in line.split("\r") if "done," in part]
    assert redraws, out
    assert all(len(part) <= 100 for part in redraws)  # fitted to the terminal's width, never wrapped
    assert any(re.search(r"\d/2 done, \d running", part) for part in redraws)
    assert redraws[-1].count("█") > 0
    # Every event is a whole line of its own (the bar is cleared before it and drawn again after).
    events = [part.strip() for line in out.split("\n") for part in line.split("\r") if "started in process" in part]
    assert sorted(re.sub(r"\d+$", "PID", e) for e in events) == ["reach2: started in process PID",
                                                                "throw: started in process PID"]
    assert re.search(r"report: .*REPORT\.md \(\d+ of \d+ claims hold", out)



def test_a_failed_piece_is_counted_apart_and_leaves_the_time_left(monkeypatch):
    clock = _Clock()
    monkeypatch.setattr(status_module.time, "monotonic", clock)
    show = Status(["td3 seed 0", "td3 seed 1", "sac seed 0"], workers=2, expected={}, stream=io.StringIO())
    show.started("td3 seed 0", "on the cluster")
    show.started("td3 seed 1", "on the cluster")
    clock.now += 10
    show.expected.update({"td3 seed 0": 10.0, "td3 seed 1": 10.0})  # learned from the first td3 unit
    show.finished("td3 seed 0")
    show.failed("td3 seed 1")
    assert show.line().startswith("1/3 done, 0 running, 1 failed")
    assert "time left unknown" in show.line()  # sac has no finished unit to go by yet
    show.expected["sac seed 0"] = 4.0
    show.started("sac seed 0", "on the cluster")
    assert show.seconds_left() == 4.0  # the failed unit is not waited for
    show.finished("sac seed 0")
    assert show.line().endswith("all done")
