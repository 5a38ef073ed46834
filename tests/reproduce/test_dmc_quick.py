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


def _learner(samples, returns, seeds):
    return {"samples": samples, "return": returns, "seeds": seeds, "seconds_per_sample": [1e-3] * len(seeds),
            "wall_seconds": [[0.1 * s] * len(seeds) for s in samples]}


def test_claims_name_each_sides_samples_and_the_peers_last_rungs_are_reported():
    results = {"dmc:point_mass-easy": {"random_action_return": 1.0, "learners": {
        "somq": _learner([100, 300], [[1.0, 3.0], [85.0, 95.0]], [30, 31]),
        "somq+": _learner([100, 300], [[1.0, 3.0], [70.0, 80.0]], [30, 31]),
        "sac": _learner([50, 100], [[10.0, 30.0], [100.0, 100.0]], [0, 1])}}}
    m = dmc.measure(results)
    assert m["dmc:point_mass-easy"]["before_last"]["sac"] == (50, 20.0)
    claims = {c.claim.split(" reaches")[0].split(": ")[1]: c for c in dmc._claims(m)
              if "point_mass" in c.claim}
    assert claims["SOM-Q"].holds is True and claims["SOM-Q+ (interpolated)"].holds is False  # 90 >= 90 > 75
    assert "after 300 samples" in claims["SOM-Q"].measured and "after 100 samples" in claims["SOM-Q"].measured
    assert dmc._trend(m)[2:] == ["- dmc:point_mass-easy: SB3 SAC 20.0 at 50 samples, 100.0 at 100"]
