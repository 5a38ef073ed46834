"""Smoke test of ``somarm bench tasks`` (figures are printed, never asserted as timings)."""

from __future__ import annotations

import json

import pytest

from somarm.perf import tasks as bench


def test_quick_benchmark_prints_a_row_per_task(capsys, tmp_path):
    assert bench.main(["--quick", "--only", "reach2", "throw", "--json", str(tmp_path / "bench.json")]) == 0
    lines = capsys.readouterr().out.splitlines()
    rows = {line.split()[0]: line.split() for line in lines[1:3]}
    assert set(rows) == {"reach2", "throw"}
    assert float(rows["throw"][4]) <= 1e-6  # the landing error column
    assert float(rows["reach2"][4]) <= 1e-9  # the fingertip error column
    figures = json.loads((tmp_path / "bench.json").read_text())["tasks"]
    assert set(figures) == {"reach2", "throw"}
    for f in figures.values():
        assert {"mujoco_per_s", "step100_ms", "step20_ms", "dm_env_us"} <= set(f)
        assert all(f[key] > 0 for key in ("mujoco_per_s", "step100_ms", "step20_ms", "dm_env_us"))
        # The printed ratio is the step's cost per evaluation over the large batch's.
        assert f["step100_x_batch"] == pytest.approx(f["step100_ms"] / 1e3 / 100 * f["mujoco_per_s"])
    # MuJoCo's CPU per projectile-step (the throws', not the arms'): some, and per throw not more than
    # the large batch's time on its threads.
    throw = figures["throw"]
    assert "mujoco_us_per_projectile_step" not in figures["reach2"] and throw["projectile_steps_per_throw"] >= 1
    cpu_per_throw = throw["mujoco_us_per_projectile_step"] * 1e-6 * throw["projectile_steps_per_throw"]
    assert 0.0 < cpu_per_throw <= 2 / throw["mujoco_per_s"]
    assert float(rows["throw"][10]) == pytest.approx(throw["mujoco_us_per_projectile_step"], abs=1e-3)
    assert rows["reach2"][10] == "-"


def test_json_into_a_missing_folder_fails_before_measuring(tmp_path):
    with pytest.raises(ValueError, match="the folder .* does not exist"):
        bench.main(["--quick", "--only", "throw", "--json", str(tmp_path / "nope" / "bench.json")])


def test_unknown_task_fails_in_one_line():
    with pytest.raises(ValueError, match="unknown task 'reach3'; tasks: reach2"):
        bench.main(["--quick", "--only", "reach3"])
