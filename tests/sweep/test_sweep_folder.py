"""A sweep folder is claimed like a run folder: one writer, another sweep only with --force, no leftovers."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

from somarm import cli
from somarm.run.claim import claim
from somarm.sweep import driver

TINY = ["--trials", "1", "--steps", "100", "--block", "50", "--no-progress", "--no-figures"]


def _sweep(out, grid: str, *extra: str) -> int:
    return cli.main(["sweep", "reach2", "--grid", grid, "--out", str(out), *TINY, *extra])


def _error(capsys) -> str:
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("somarm: error: "), err
    return err[0]


def test_another_sweep_is_refused_without_force_and_replaces_the_first_with_it(tmp_path, capsys):
    out = tmp_path / "sweep"
    assert _sweep(out, "lambda_a=0.5,1") == 0
    first = (out / "results.csv").read_text()
    (out / "notes.txt").write_text("mine")
    capsys.readouterr()
    assert _sweep(out, "alpha=0.2,0.3") == 2  # another swept key: another sweep
    assert "holds another sweep" in _error(capsys) and (out / "results.csv").read_text() == first
    assert _sweep(out, "lambda_a=0.5,1") == 0  # the same sweep again: resumed, nothing to run
    assert (out / "results.csv").read_text() == first
    capsys.readouterr()
    assert _sweep(out, "alpha=0.2,0.3", "--force") == 0
    # The preset's alpha=1 is not among the swept values: said so, not that alpha was not swept.
    assert "preset table1 has alpha=1 (best x0.3) (a point this sweep did not run)" in capsys.readouterr().out
    rows = (out / "results.csv").read_text()
    assert "0.2" in rows and "lambda_a" not in rows.split("\n", 1)[0]
    assert (out / "notes.txt").read_text() == "mine"
    assert json.loads((out / "sweep.json").read_text())["points"] == [{"alpha": "0.2"}, {"alpha": "0.3"}]


def test_a_sweep_into_a_run_folder_is_refused_and_leaves_it_alone(tmp_path, capsys):
    out = tmp_path / "run"
    assert cli.main(["train", "reach2", "--steps", "100", "--no-progress", "--no-figures", "--out", str(out)]) == 0
    before = sorted(p.name for p in out.iterdir())
    capsys.readouterr()
    assert _sweep(out, "alpha=0.5,1") == 2
    assert "is not empty" in _error(capsys) and sorted(p.name for p in out.iterdir()) == before


def test_a_second_sweep_into_a_folder_being_written_is_refused(tmp_path, capsys):
    out = tmp_path / "sweep"
    held = claim(out)  # as another somarm process writing there would
    try:
        assert _sweep(out, "alpha=0.5,1") == 2
        assert "being written by another somarm process" in _error(capsys)
    finally:
        held.release()
    assert not (out / "sweep.json").exists()


def test_a_missing_engine_is_named_before_anything_is_created(tmp_path, capsys, monkeypatch):
    real = driver.importlib.util.find_spec
    monkeypatch.setattr(driver.importlib.util, "find_spec", lambda name: None if name == "ray" else real(name))
    out = tmp_path / "sweep"
    assert _sweep(out, "alpha=0.5,1", "--engine", "ray") == 2
    assert "the ray engine needs Ray Tune" in _error(capsys) and not out.exists()


def test_two_sweeps_started_at_once_leave_one_sweeps_results(tmp_path):
    out = tmp_path / "sweep"
    command = [sys.executable, "-m", "somarm.cli", "sweep", "reach2", "--out", str(out), "--trials", "1",
               "--steps", "2000", "--no-progress", "--no-figures"]
    first = subprocess.Popen([*command, "--grid", "alpha=0.5,1"], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                             text=True)
    second = subprocess.Popen([*command, "--grid", "lambda_a=0.2,0.3"], stdout=subprocess.PIPE,
                              stderr=subprocess.PIPE, text=True)
    results = [(p.wait(timeout=300), p.stderr.read()) for p in (first, second)]
    codes = sorted(code for code, _ in results)
    assert codes == [0, 2], results
    refused = next(err for code, err in results if code == 2).strip().splitlines()
    assert len(refused) == 1 and ("being written by another" in refused[0] or "holds another sweep" in refused[0])
    won = next(i for i, (code, _) in enumerate(results) if code == 0)
    points = json.loads((out / "sweep.json").read_text())["points"]
    assert points == ([{"alpha": "0.5"}, {"alpha": "1"}], [{"lambda_a": "0.2"}, {"lambda_a": "0.3"}])[won]


@pytest.fixture(autouse=True)
def _no_display(monkeypatch):
    monkeypatch.setenv("MUJOCO_GL", "disable")


def test_a_widened_sweep_resumes_in_place_and_runs_only_its_new_rows(tmp_path, capsys):
    out = tmp_path / "sweep"
    assert _sweep(out, "alpha=0.5,1") == 0
    first = {p.name: p.read_bytes() for p in (out / "points").iterdir()}
    capsys.readouterr()
    assert _sweep(out, "alpha=0.5,1,0.7", "--seeds", "2") == 0
    assert "6 of 6 runs done" in capsys.readouterr().out
    points = {p.name: p.read_bytes() for p in (out / "points").iterdir()}
    assert len(points) == 6 and all(points[name] == data for name, data in first.items())  # not run again


def test_a_sweep_in_which_no_point_finished_fails_in_one_line(tmp_path, capsys, monkeypatch):
    from somarm.run import group

    def broken(config, task):
        raise FloatingPointError("the learner diverged")

    monkeypatch.setattr(group, "make_learner", broken)
    out = tmp_path / "sweep"
    assert _sweep(out, "alpha=0.5,1") == 2
    assert "no point of the sweep finished (the first failed with: FloatingPointError" in _error(capsys)
    assert (out / "results.csv").is_file()  # each point's error is listed there


@pytest.mark.parametrize("size", ["nan", "inf", "0", "-5"])
def test_a_group_size_that_is_not_a_positive_number_is_refused(tmp_path, capsys, size):
    assert _sweep(tmp_path / "sweep", "alpha=0.5,1", "--max-group-mb", size) == 2
    assert "--max-group-mb must be" in _error(capsys)


def test_a_point_file_holding_nan_is_run_again_not_taken_as_a_result(tmp_path, capsys):
    out = tmp_path / "sweep"
    assert _sweep(out, "alpha=0.5,1") == 0
    damaged = sorted((out / "points").iterdir())[0]
    row = json.loads(damaged.read_text())
    good = row["greedy_error"]
    damaged.write_text(json.dumps({**row, "greedy_error": float("nan")}))
    capsys.readouterr()
    assert _sweep(out, "alpha=0.5,1") == 0
    assert json.loads(damaged.read_text())["greedy_error"] == good  # run again, the same number
    assert "nan" not in (out / "best.json").read_text().lower()
