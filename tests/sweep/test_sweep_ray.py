"""The Ray engine on a local Ray cluster that the test starts and stops (the ``sweep`` extra).

Skipped with the reason when Ray is missing, except in CI (``CI=true``), where a missing Ray fails:
``.ci/run`` installs the extra. Ray's state goes to a temporary folder and its auth token to a
temporary home, both removed afterwards.
"""

import csv
import os
import shutil
import tempfile
from pathlib import Path

import pytest
from ray_home import ray_home

from somarm.sweep import SweepSpec, parse_grid, run_sweep

try:
    import ray
except ImportError:  # pragma: no cover - depends on the installation
    ray = None
    if os.environ.get("CI", "").lower() in ("1", "true", "yes"):
        pytest.fail('CI must test the Ray engine: install the extra (pip install -e ".[sweep]")',
                    pytrace=False)
    pytestmark = pytest.mark.skip(reason='Ray is not installed (pip install -e ".[sweep]")')


@pytest.fixture
def ray_cluster(tmp_path, monkeypatch):
    from somarm.sweep.ray_engine import start_local

    real_home = Path.home()
    had_ray_folder = (real_home / ".ray").exists()
    state = tempfile.mkdtemp(prefix="ray", dir="/tmp")  # short: Ray's socket paths must fit 107 bytes
    monkeypatch.setenv("HOME", str(ray_home()))  # where Ray writes its auth token (one folder per process)
    monkeypatch.setenv("RAY_TMPDIR", state)
    start_local(1, _temp_dir=state)
    try:
        yield
    finally:
        ray.shutdown()
        shutil.rmtree(state, ignore_errors=True)
    assert (real_home / ".ray").exists() == had_ray_folder  # nothing left in the real home folder


def metrics(path):
    with open(path) as handle:
        return [(r["point"], r["seed"], r["greedy_error"], r["final_error"], r["error"]) for r in csv.DictReader(handle)]


def test_the_ray_engine_gives_the_local_engines_numbers_and_restores_its_experiment(ray_cluster, tmp_path):
    # Two points in one Tune trial (one lockstep group) keep this short: a cold Ray costs ~10 s.
    spec = SweepSpec(task="reach2", axes=(parse_grid("alpha=0.5,1"),), n_trials=2, n_steps=100, block=50)
    on_ray = run_sweep(spec, tmp_path / "ray", engine="ray", progress=False, figure=False)
    run_sweep(spec, tmp_path / "local", engine="local", progress=False, figure=False)
    assert not on_ray.interrupted and on_ray.n_run == 2
    assert metrics(tmp_path / "ray" / "results.csv") == metrics(tmp_path / "local" / "results.csv")
    assert len(metrics(tmp_path / "local" / "results.csv")) == 2
    experiments = list((tmp_path / "ray" / "ray").iterdir())
    assert len(experiments) == 1 and (experiments[0] / "tuner.pkl").is_file()  # Tune's storage_path is in DIR

    # Lose the rows: the rerun restores the finished Tune experiment instead of training again.
    for row in (tmp_path / "ray" / "points").iterdir():
        row.unlink()
    again = run_sweep(spec, tmp_path / "ray", engine="ray", progress=False, figure=False)
    assert again.n_run == 2 and metrics(tmp_path / "ray" / "results.csv") == metrics(tmp_path / "local" / "results.csv")
    assert list((tmp_path / "ray" / "ray").iterdir()) == experiments
