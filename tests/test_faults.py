"""Faults injected on real runs: damaged files, (later) full disks, concurrent writers, double signals.

Every fault ends in one line naming what is wrong (``somarm: error: ...``), never a traceback.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from somarm import learners, training

ROOT = Path(__file__).resolve().parents[1]
ENV = dict(os.environ, MUJOCO_GL="disable", PYTHONPATH=str(ROOT))


def somarm(*argv: str, timeout: float = 120, **kwargs) -> subprocess.CompletedProcess:
    """Run the ``somarm`` command line in a fresh process."""
    return subprocess.run([sys.executable, "-m", "somarm.cli", *argv], capture_output=True, text=True,
                          env=ENV, timeout=timeout, **kwargs)


def one_error_line(done: subprocess.CompletedProcess, *needles: str) -> str:
    """The process failed with exit code 2 and one ``somarm: error:`` line holding every needle."""
    lines = done.stderr.strip().splitlines()
    assert done.returncode == 2 and len(lines) == 1, done.stderr
    assert lines[0].startswith("somarm: error: "), lines[0]
    for needle in needles:
        assert needle in lines[0], lines[0]
    return lines[0]


@pytest.fixture(scope="module")
def run_folder(tmp_path_factory) -> Path:
    """A small trained reach2 run (two trials), written as `somarm train` writes it."""
    out = tmp_path_factory.mktemp("run") / "reach2"
    result = training.train(training.RunConfig(task="reach2", n_trials=2, n_steps=200, seed=1), progress=False)
    training.write_run(result, out, figures=False)
    return out


def _rewrite_meta(src: Path, dst: Path, change) -> None:
    with np.load(src, allow_pickle=False) as data:
        arrays = {name: data[name] for name in data.files}
    meta = json.loads(str(arrays["meta"]))
    arrays["meta"] = np.array(json.dumps(change(meta)))
    np.savez_compressed(dst, **arrays)


def _without(key):
    def change(meta):
        meta.pop(key)
        return meta
    return change


def _with(key, value):
    def change(meta):
        meta[key] = value
        return meta
    return change


DAMAGES = {
    "meta is a list": (lambda meta: [meta], "not an object"),
    "no bounds": (_without("bounds"), "'bounds'"),
    "streams empty": (_with("streams", {}), "'streams' lacks"),
    "config null": (_with("config", None), "'config'"),
    "bounds of three": (_with("bounds", [[0.0], [1.0], [0.0]]), "'bounds'"),
    "t a string": (_with("t", "12"), "'t'"),
}


@pytest.mark.parametrize("damage", sorted(DAMAGES))
def test_damaged_learner_meta_is_one_line_naming_the_file(damage, run_folder, tmp_path):
    change, needle = DAMAGES[damage]
    path = tmp_path / "learner.npz"
    _rewrite_meta(run_folder / "learner.npz", path, change)
    with pytest.raises(ValueError, match="damaged learner file") as caught:
        learners.load_learner(path)
    assert str(path) in str(caught.value) and needle in str(caught.value)
    assert len(str(caught.value).splitlines()) == 1


def test_damaged_learner_array_names_the_file(run_folder, tmp_path):
    with np.load(run_folder / "learner.npz", allow_pickle=False) as data:
        arrays = {name: data[name] for name in data.files if name != "q"}
    path = tmp_path / "learner.npz"
    np.savez_compressed(path, **arrays)
    with pytest.raises(ValueError, match=f"{path} is a damaged learner file: array 'q' is missing"):
        learners.load_learner(path)


def _copy_run(run_folder: Path, dst: Path) -> Path:
    dst.mkdir()
    for name in ("config.json", "learner.npz", "curves.npz", "summary.json"):
        (dst / name).write_bytes((run_folder / name).read_bytes())
    return dst


def test_a_learner_of_another_kind_or_task_is_refused(run_folder, tmp_path):
    other = _copy_run(run_folder, tmp_path / "kind")
    config = json.loads((other / "config.json").read_text())
    (other / "config.json").write_text(json.dumps({**config, "learner": "motoric"}))
    with pytest.raises(ValueError, match="does not belong to .*holds a somq learner, the config says motoric"):
        training.load_run(other)
    throw = _copy_run(run_folder, tmp_path / "task")
    (throw / "config.json").write_text(json.dumps({**config, "task": "four_goals"}))
    training.load_run(throw)  # four_goals has reach2's bounds: accepted
    (throw / "config.json").write_text(json.dumps({**config, "task": "reach20"}))
    with pytest.raises(ValueError, match="bounds are not those of task 'reach20'"):
        training.load_run(throw)
    (throw / "config.json").write_text(json.dumps({**config, "seed": -4}))
    with pytest.raises(ValueError, match="seed must be a whole number >= 0"):
        training.load_run(throw)


def test_evaluate_and_view_of_a_damaged_run_end_in_one_line(run_folder, tmp_path):
    bad = _copy_run(run_folder, tmp_path / "bad")
    _rewrite_meta(run_folder / "learner.npz", bad / "learner.npz", _with("streams", {}))
    one_error_line(somarm("evaluate", str(bad)), str(bad / "learner.npz"), "damaged")
    one_error_line(somarm("view", "reach2", "--run", str(bad), "--html", str(tmp_path / "x.html")),
                   str(bad / "learner.npz"), "damaged")


# -- trial ids (a run of --trial-ids 7 is trial 7 everywhere) ------------------------------------
@pytest.fixture(scope="module")
def trial7_run(tmp_path_factory) -> tuple[Path, list[str]]:
    from somarm import plots

    out = tmp_path_factory.mktemp("trial7")
    titles: list[str] = []
    save = plots.save

    def record(fig, path):
        titles.extend(ax.get_title() for ax in fig.axes)
        return save(fig, path)

    plots.save = record
    try:
        config = training.RunConfig(task="reach2", n_trials=1, trial_ids=[7], n_steps=200, seed=2)
        training.write_run(training.train(config, progress=False), out)
    finally:
        plots.save = save
    return out, titles


def test_figures_name_the_trial_id(trial7_run):
    _, titles = trial7_run
    maps = [title for title in titles if "map" in title]
    assert len(maps) == 2 and all("(trial 7)" in title for title in maps), titles


def test_view_takes_the_trial_id(trial7_run, tmp_path):
    from somarm.viewer.sessions import load_session

    run, _ = trial7_run
    by_default = load_session("reach2", run=run, n_goals=3)
    by_id = load_session("reach2", run=run, n_goals=3, trial=7)
    np.testing.assert_array_equal(by_default.actions, by_id.actions)
    with pytest.raises(ValueError, match=r"--trial must be one of this run's trials \(7\), got 0"):
        load_session("reach2", run=run, n_goals=3, trial=0)


# -- the viewer's faults ---------------------------------------------------------------------------
def test_viewer_port_in_use_and_bad_host_are_one_line(tmp_path, capsys):
    import socket

    from somarm.cli import main

    def error_line() -> str:
        lines = capsys.readouterr().err.strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith("somarm: error: "), lines
        return lines[0]

    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        assert main(["view", "reach2", "--port", str(port), "--goals", "2"]) == 2
        assert f"--port {port}: [Errno 98] Address already in use" in error_line()
        out = tmp_path / "run"
        assert main(["train", "reach2", "--view", "--port", str(port), "--out", str(out)]) == 2
        assert "Address already in use" in error_line()
        assert not out.exists()  # nothing ran: no empty run folder
    assert main(["view", "reach2", "--host", "no.such.host.invalid", "--goals", "2"]) == 2
    assert "could not start on --host no.such.host.invalid: " in error_line()
