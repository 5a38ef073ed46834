"""``somarm compare --engine ray`` (and ``reproduce``'s) on a local Ray of 2 worker CPUs: the same numbers as a
run here, a worker killed mid-unit run again, a killed driver resumed.

Skipped with the reason when Ray is missing, except in CI (``CI=true``), where a missing Ray fails. Ray's state
goes to a temporary folder and its auth token to a temporary home, both removed afterwards.
"""

from __future__ import annotations

import json
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

import pytest
from ray_home import ray_home

from somarm.peers import compare

try:
    import ray
except ImportError:  # pragma: no cover - depends on the installation
    ray = None
    pytestmark = pytest.mark.skip(reason='Ray is not installed (pip install -e ".[sweep]")')

#: Two learners at two seeds on reach2, each unit a second or two of training.
CONFIG = compare.CompareConfig(task="reach2", learners=("somq", "tabular"), samples=6000, seeds=2, observations=50)


@pytest.fixture(scope="module")
def cluster():
    """A local Ray of 2 CPUs for the module; its address (drivers in other processes join it)."""
    from somarm.sweep.ray_engine import start_local

    state = tempfile.mkdtemp(prefix="ray", dir="/tmp")  # short: Ray's socket paths must fit 107 bytes
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv("HOME", str(ray_home()))  # where Ray writes its auth token (one folder per process)
        patch.setenv("RAY_TMPDIR", state)
        start_local(2, _temp_dir=state)
        try:
            yield ray.get_runtime_context().gcs_address
        finally:
            ray.shutdown()
            shutil.rmtree(state, ignore_errors=True)


def _scores(folder: Path) -> dict:
    """What a comparison found, without its wall times (a measure of this run, not a result)."""
    result = json.loads((folder / "compare.json").read_text())
    for data in result["learners"].values():
        data.pop("wall_seconds")
        data.pop("seconds_per_sample")
    records = {p.name: json.loads(p.read_text()) for p in sorted((folder / "seeds").glob("*.json"))}
    for record in records.values():
        record.pop("walls")
    return {"compare": result, "records": records}


@pytest.fixture(scope="module")
def here(tmp_path_factory):
    """The comparison run in this process, as every engine must find it."""
    folder = tmp_path_factory.mktemp("here")
    compare.compare(CONFIG, folder, progress=False)
    return _scores(folder)


def test_on_ray_every_unit_finds_what_it_finds_here(cluster, here, tmp_path):
    compare.compare(CONFIG, tmp_path, progress=False, engine="ray", address=cluster)
    assert _scores(tmp_path) == here
    assert len(here["records"]) == 4


def _unit_processes() -> list[int]:
    """The Ray worker processes running a comparison's unit now (Ray titles them by the task's function)."""
    found = []
    for entry in Path("/proc").iterdir():
        try:
            if entry.name.isdigit() and (entry / "cmdline").read_bytes().startswith(b"ray::run_unit"):
                found.append(int(entry.name))
        except OSError:
            continue
    return found


def test_a_worker_killed_mid_unit_has_its_unit_run_again_with_the_same_result(cluster, here, tmp_path):
    killed: list[int] = []

    def kill_the_first_unit() -> None:
        deadline = time.monotonic() + 60
        while not killed and time.monotonic() < deadline:
            for pid in _unit_processes():
                os.kill(pid, signal.SIGKILL)
                killed.append(pid)
                break
            time.sleep(0.05)

    killer = threading.Thread(target=kill_the_first_unit)
    killer.start()
    try:
        compare.compare(CONFIG, tmp_path, progress=False, engine="ray", address=cluster)
    finally:
        killer.join()
    assert killed, "no unit was seen running"
    assert _scores(tmp_path) == here


def test_a_killed_driver_resumed_keeps_the_units_that_came_back(cluster, here, tmp_path):
    argv = [sys.executable, "-m", "somarm.cli", "compare", "reach2", "--learners", "somq,tabular", "--samples",
            "6000", "--seeds", "2", "--observations", "50", "--engine", "ray", "--ray-address", cluster,
            "--out", str(tmp_path), "--resume"]  # from its first start: a long run writes its records in place
    driver = subprocess.Popen(argv, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, env={**os.environ})
    try:
        deadline = time.monotonic() + 120
        while not list((tmp_path / "seeds").glob("*.json")) and time.monotonic() < deadline:
            time.sleep(0.05)
        kept = sorted(p.name for p in (tmp_path / "seeds").glob("*.json"))
        driver.send_signal(signal.SIGKILL)
        driver.wait(timeout=30)
    finally:
        driver.kill()
    assert 1 <= len(kept) < 4, kept  # killed with some units back and some not
    before = {name: (tmp_path / "seeds" / name).read_text() for name in kept}
    done = subprocess.run(argv, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    assert done.stderr.count("(kept from the earlier run)") >= len(kept)
    assert all((tmp_path / "seeds" / name).read_text() == text for name, text in before.items())  # not run again
    assert _scores(tmp_path) == here


def test_reproduce_on_ray_writes_the_report_a_run_here_writes(cluster, tmp_path):
    from somarm.reproduce import runner

    only = ["throw", "reach20", "four_goals"]
    assert runner.reproduce(tmp_path / "here", quick=True, only=only, progress=False, backend="analytic") == 0
    assert runner.reproduce(tmp_path / "ray", quick=True, only=only, progress=False, backend="analytic",
                            engine="ray", address=cluster) == 0
    claims = [runner.load_claims(tmp_path / name) for name in ("here", "ray")]
    for found in claims:
        found.pop("wall_time_s")
        for part in found["experiments"].values():
            part.pop("wall_time_s")
    assert claims[0] == claims[1]
    figures = sorted(p.name for p in (tmp_path / "here" / "figures").iterdir())
    assert figures == sorted(p.name for p in (tmp_path / "ray" / "figures").iterdir())
    for name in figures:  # sent back over the wire and written here, byte for byte
        assert (tmp_path / "here" / "figures" / name).read_bytes() == (tmp_path / "ray" / "figures" / name).read_bytes()
    report = (tmp_path / "ray" / "REPORT.md").read_text()
    assert "figures/" in report and str(tmp_path) not in report
