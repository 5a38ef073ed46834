"""``somarm reproduce --jobs N``: experiments in worker processes, the same report, clean stops."""

from __future__ import annotations

import json
import os
import re
import signal
import subprocess
import sys
import time

import pytest
from processes import survivors_of_a_killed_parent

from somarm.reproduce import runner

_ENV = {**os.environ, "MUJOCO_GL": "disable"}


def _claims_without_times(out) -> dict:
    claims = runner.load_claims(out)
    claims.pop("wall_time_s", None)
    for part in claims["experiments"].values():
        part.pop("wall_time_s", None)
    return claims


def test_workers_write_the_report_a_single_process_writes(tmp_path):
    only = ["throw", "reach20", "four_goals"]
    assert runner.reproduce(tmp_path / "one", quick=True, only=only, progress=False, backend="analytic") == 0
    assert runner.reproduce(tmp_path / "two", quick=True, only=only, progress=False, backend="analytic", jobs=2) == 0
    assert _claims_without_times(tmp_path / "two") == _claims_without_times(tmp_path / "one")
    # In the order asked for, whatever order the workers finished in, and the same figures, byte for byte.
    report = (tmp_path / "two" / "REPORT.md").read_text()
    places = [report.index(f"Experiment `{name}`") for name in only]
    assert places == sorted(places)
    figures = sorted(p.name for p in (tmp_path / "one" / "figures").iterdir())
    assert figures and figures == sorted(p.name for p in (tmp_path / "two" / "figures").iterdir())
    for name in figures:
        assert (tmp_path / "one" / "figures" / name).read_bytes() == (tmp_path / "two" / "figures" / name).read_bytes()


def test_jobs_default_to_the_cores_and_one_experiment_runs_in_this_process(tmp_path, monkeypatch):
    from somarm import cli
    from somarm.reproduce import parallel

    asked = []
    monkeypatch.setattr(runner, "reproduce", lambda out, **kwargs: asked.append(kwargs["jobs"]) or 0)
    assert cli.main(["reproduce", "--quick", "--only", "throw", "--out", str(tmp_path / "a")]) == 0
    assert cli.main(["reproduce", "--quick", "--only", "throw", "--jobs", "1", "--out", str(tmp_path / "b")]) == 0
    assert asked == [len(os.sched_getaffinity(0)), 1] and runner.default_jobs() == asked[0]
    monkeypatch.undo()
    # More jobs than experiments: the one experiment runs here (no worker process to start).
    monkeypatch.setattr(parallel, "run", lambda *args, **kwargs: pytest.fail("a worker for one experiment"))
    assert runner.reproduce(tmp_path / "c", quick=True, only=["throw"], progress=False, backend="analytic",
                            jobs=2) == 0


def test_ctrl_c_stops_every_worker_and_keeps_the_finished_experiments(tmp_path):
    # throw (quick) ends seconds before more_inputs; the signal goes to the parent alone, right then.
    proc = subprocess.Popen(
        [sys.executable, "-m", "somarm.cli", "reproduce", "--quick", "--jobs", "2", "--out", str(tmp_path),
         "--only", "throw", "more_inputs"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=_ENV,
    )
    pids, lines = [], []
    try:
        deadline = time.monotonic() + 120
        while time.monotonic() < deadline:
            line = proc.stderr.readline()
            lines.append(line)
            if started := re.match(r"\w+: started in process (\d+)", line):
                pids.append(int(started.group(1)))
            if line.startswith("throw: ") and "started" not in line:
                break
        proc.send_signal(signal.SIGINT)
        _, err = proc.communicate(timeout=120)
    finally:
        proc.kill()
    assert proc.returncode == 130, "".join(lines) + err
    assert "Traceback" not in err
    # Into a pipe the status is whole lines, never a bar redrawn with carriage returns.
    assert "\r" not in "".join(lines) + err and "█" not in "".join(lines) + err
    claims = runner.load_claims(tmp_path)
    assert claims["complete"] is False and list(claims["experiments"]) == ["throw"]
    assert len(pids) == 2
    for pid in pids:  # no worker is left behind
        try:
            os.kill(pid, 0)
        except ProcessLookupError:
            continue
        raise AssertionError(f"worker {pid} still runs")


def test_a_full_disk_in_a_worker_is_one_line_and_keeps_a_valid_report(small_disk):
    out = small_disk / "report"
    free = os.statvfs(small_disk).f_bavail * os.statvfs(small_disk).f_frsize
    (small_disk / "filler").write_bytes(b"\0" * max(0, free - 256 * 1024))  # room for a few figures only
    done = subprocess.run(
        [sys.executable, "-m", "somarm.cli", "reproduce", "--quick", "--jobs", "2", "--out", str(out),
         "--only", "throw", "throw_maps", "--no-progress"],
        capture_output=True, text=True, env=_ENV, timeout=300,
    )
    assert done.returncode == 2, done.stderr
    last = done.stderr.strip().splitlines()[-1]
    assert last.startswith("somarm: error:") and "No space left" in last and "Traceback" not in done.stderr
    assert re.search(r"the report keeps the \d experiment\(s\) that finished$", last)
    if (out / "claims.json").exists():  # whatever finished is reported, never a half-written file
        assert json.loads((out / "claims.json").read_text())["complete"] is False


def test_bad_jobs_is_one_line(tmp_path):
    done = subprocess.run([sys.executable, "-m", "somarm.cli", "reproduce", "--quick", "--jobs", "0", "--out",
                           str(tmp_path / "r")], capture_output=True, text=True, env=_ENV)
    assert done.returncode == 2 and done.stderr.strip() == "somarm: error: --jobs must be a whole number >= 1, got 0"


def test_a_killed_parent_leaves_no_worker_running(tmp_path):
    # SIGKILL gives the parent no chance to stop its workers: Fig. 25 at full length (minutes, its
    # group shared with a process of the worker's own) must still stop within seconds, all of it.
    proc = subprocess.Popen(
        [sys.executable, "-m", "somarm.cli", "reproduce", "--jobs", "2", "--out", str(tmp_path),
         "--only", "more_inputs", "reach20"],  # two: one alone would run in the parent
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=_ENV,
    )
    try:
        line = ""
        deadline = time.monotonic() + 60
        while not (started := re.match(r"more_inputs: started in process (\d+)", line)) and time.monotonic() < deadline:
            line = proc.stderr.readline()
        assert started, line
        worker = int(started.group(1))
        time.sleep(10)  # the worker's group under way, its share process started
        family = [worker, *map(int, subprocess.run(["pgrep", "-P", str(worker)], capture_output=True,
                                                   text=True).stdout.split())]
        assert len(family) >= 2, "the worker shares Fig. 25's group with a process of its own"
        left = survivors_of_a_killed_parent(proc, family, 45)  # each stops between two steps
        err = proc.stderr.read()  # the workers share the parent's stderr; closed once they end
    finally:
        proc.kill()
    assert not left, f"process(es) {left} still running after the parent died"
    assert "Traceback" not in err and "KeyboardInterrupt" not in err, err



def test_workers_of_a_killed_parent_end_without_a_traceback(tmp_path):
    proc = subprocess.Popen(
        [sys.executable, "-m", "somarm.cli", "reproduce", "--quick", "--jobs", "2", "--out", str(tmp_path)],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=_ENV,
    )
    try:
        workers, line = set(), ""
        deadline = time.monotonic() + 60
        while len(workers) < 2 and time.monotonic() < deadline:  # both workers busy
            line = proc.stderr.readline()
            if started := re.match(r"\w+: started in process (\d+)", line):
                workers.add(int(started.group(1)))
        assert len(workers) == 2, line
        left = survivors_of_a_killed_parent(proc, sorted(workers), 45)
        err = proc.stderr.read()
    finally:
        proc.kill()
    assert not left, f"process(es) {left} still running after the parent died"
    assert "Traceback" not in err and "KeyboardInterrupt" not in err, err
