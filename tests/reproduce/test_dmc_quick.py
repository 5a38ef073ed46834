"""The dmc report part end to end in quick mode: every task and learner, then the report again from the records."""

import json

import pytest

from somarm.reproduce import dmc


def _end_to_end(tmp_path):
    pytest.importorskip("stable_baselines3")
    from somarm.reproduce import runner

    assert runner.reproduce(tmp_path, quick=True, only=["dmc"], progress=False) == 0
    report = (tmp_path / "REPORT.md").read_text()
    for task in dmc.TASKS:
        result = json.loads((tmp_path / "dmc" / task[4:] / "compare.json").read_text())
        assert set(result["learners"]) == set(dmc.LEARNERS) and result["task"] == task
        assert result["task_params"]["time_limit"] == dmc.QUICK_PARAMS["time_limit"]
        assert (tmp_path / "dmc" / task[4:] / "compare.png").stat().st_size > 0
        assert task in report
    assert "The peers' last two rungs" in report
    # Written again from the records alone: the same numbers, nothing trained.
    before = {p: p.stat().st_mtime_ns for p in (tmp_path / "dmc").rglob("seeds/*.json")}
    assert runner.reproduce(tmp_path, quick=True, only=["dmc_recorded"], progress=False) == 0
    assert {p: p.stat().st_mtime_ns for p in (tmp_path / "dmc").rglob("seeds/*.json")} == before


def test_the_part_runs_end_to_end_in_quick_mode_on_one_task(tmp_path, monkeypatch):
    monkeypatch.setattr(dmc, "TASKS", ("dmc:cartpole-balance",))
    _end_to_end(tmp_path)


@pytest.mark.slow
def test_the_part_runs_end_to_end_in_quick_mode(tmp_path):
    _end_to_end(tmp_path)
