"""Faults injected on real runs: damaged files, (later) full disks, concurrent writers, double signals.

Every fault ends in one line naming what is wrong (``somarm: error: ...``), never a traceback.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from somarm import learners, run

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
    result = run.train(run.RunConfig(task="reach2", n_trials=2, n_steps=200, seed=1), progress=False)
    run.write(result, out, figures=False)
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
        learners.load(path)
    assert str(path) in str(caught.value) and needle in str(caught.value)
    assert len(str(caught.value).splitlines()) == 1


def test_damaged_learner_array_names_the_file(run_folder, tmp_path):
    with np.load(run_folder / "learner.npz", allow_pickle=False) as data:
        arrays = {name: data[name] for name in data.files if name != "q"}
    path = tmp_path / "learner.npz"
    np.savez_compressed(path, **arrays)
    with pytest.raises(ValueError, match=f"{path} is a damaged learner file: array 'q' is missing"):
        learners.load(path)


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
        run.load(other)
    throw = _copy_run(run_folder, tmp_path / "task")
    (throw / "config.json").write_text(json.dumps({**config, "task": "four_goals"}))
    run.load(throw)  # four_goals has reach2's bounds: accepted
    (throw / "config.json").write_text(json.dumps({**config, "task": "reach20"}))
    with pytest.raises(ValueError, match="bounds are not those of task 'reach20'"):
        run.load(throw)
    (throw / "config.json").write_text(json.dumps({**config, "seed": -4}))
    with pytest.raises(ValueError, match="seed must be a whole number >= 0"):
        run.load(throw)


def test_a_learner_whose_settings_are_not_the_configs_is_refused_naming_the_file(run_folder, tmp_path):
    other = _copy_run(run_folder, tmp_path / "maps")
    config = json.loads((other / "config.json").read_text())
    (other / "config.json").write_text(json.dumps({**config, "overrides": {"input_shape": "5x5"}}))
    one_error_line(somarm("evaluate", str(other)), str(other / "learner.npz"), "does not belong to",
                   "its settings differ: input_shape")
    (other / "config.json").write_text(json.dumps({**config, "overrides": {"alpha": "nan"}}))
    one_error_line(somarm("evaluate", str(other)), str(other / "config.json"), "alpha must be finite")


def test_a_learned_state_of_nan_is_a_damaged_file(run_folder, tmp_path):
    bad = _copy_run(run_folder, tmp_path / "nan")
    with np.load(run_folder / "learner.npz", allow_pickle=False) as data:
        arrays = {name: data[name] for name in data.files}
    arrays["q"] = np.full_like(arrays["q"], np.nan)
    np.savez_compressed(bad / "learner.npz", **arrays)
    one_error_line(somarm("evaluate", str(bad)), str(bad / "learner.npz"), "q holds NaN or infinite values")


def test_a_config_nested_beyond_any_limit_is_one_line(run_folder, tmp_path):
    deep = _copy_run(run_folder, tmp_path / "deep")
    (deep / "config.json").write_text("[" * 100_000)
    one_error_line(somarm("evaluate", str(deep)), str(deep / "config.json"), "nested too deeply")


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
        config = run.RunConfig(task="reach2", n_trials=1, trial_ids=[7], n_steps=200, seed=2)
        run.write(run.train(config, progress=False), out)
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


# -- a full disk -----------------------------------------------------------------------------------
def _fill(disk: Path, leave: int) -> None:
    """Fill ``disk`` until only ``leave`` bytes (whole 4 KiB pages) are free."""
    free = os.statvfs(disk).f_bavail * os.statvfs(disk).f_frsize
    (disk / "filler").write_bytes(b"\0" * max(0, free - leave))


def _pages(n_bytes: int) -> int:
    return -(-n_bytes // 4096) * 4096


def test_a_full_disk_keeps_the_learner_and_names_the_file(small_disk, run_folder, tmp_path, capsys):
    from somarm.cli import main

    # Room for the learner, its config, the curves and the summary, but not for the figures.
    sizes = {name: (run_folder / name).stat().st_size for name in ("learner.npz", "config.json", "curves.npz",
                                                                      "summary.json")}
    _fill(small_disk, sum(_pages(n) for n in sizes.values()) + 4096)
    out = small_disk / "run"
    done = somarm("train", "reach2", "--trials", "2", "--steps", "200", "--seed", "1", "--no-progress",
                  "--out", str(out))
    line = one_error_line(done, "learning_curve.png", "No space left on device", "kept learner.npz, config.json")
    assert "Traceback" not in line
    assert main(["evaluate", str(out)]) == 0  # the trained learner was kept, and it is the one trained
    _, learner = run.load(out)
    np.testing.assert_array_equal(learner.q, learners.load(run_folder / "learner.npz").q)
    assert not list(out.glob(".*.tmp"))  # no half-written temporary left
    capsys.readouterr()
    assert main(["view", "reach2", "--html", str(small_disk / "reach2.html"), "--goals", "2"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "reach2.html: No space left on device" in err[0], err


def test_a_disk_with_no_room_for_the_learner_says_so(small_disk):
    _fill(small_disk, 4096)
    out = small_disk / "run"
    one_error_line(somarm("train", "reach2", "--steps", "100", "--no-progress", "--out", str(out)),
                   "learner.npz: No space left on device", "nothing was written")


# -- concurrent writers, existing folders, double signals ------------------------------------------
def _start_training(out: Path, *extra: str) -> subprocess.Popen:
    """A long `somarm train` that has started training when this returns (its first progress line)."""
    proc = subprocess.Popen([sys.executable, "-m", "somarm.cli", "train", "reach2", "--steps", "50000000",
                             "--out", str(out), *extra], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, env=ENV)
    line = proc.stderr.readline()
    assert "mean reward" in line, line + proc.stderr.read()
    return proc


def test_a_second_writer_is_refused_while_the_first_runs(tmp_path):
    out = tmp_path / "run"
    first = _start_training(out, "--seed", "3")
    try:
        one_error_line(somarm("train", "reach2", "--steps", "100", "--seed", "4", "--out", str(out)),
                       f"--out {out} is being written by another somarm process (pid {first.pid})")
        first.send_signal(signal.SIGINT)
        _, err = first.communicate(timeout=120)
    finally:
        first.kill()
    assert first.returncode == 130, err
    assert json.loads((out / "config.json").read_text())["seed"] == 3  # only the first writer's files
    assert json.loads((out / "summary.json").read_text())["seed"] == 3


def test_an_existing_run_is_refused_and_force_clears_it(tmp_path, capsys):
    from somarm.cli import main

    out = tmp_path / "run"
    assert main(["train", "reach2", "--steps", "100", "--no-progress", "--out", str(out)]) == 0
    assert (out / "learning_curve.png").is_file()
    capsys.readouterr()
    assert main(["train", "throw", "--steps", "100", "--no-progress", "--no-figures", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert f"--out {out} is not empty" in err and "give --force to replace a run there" in err
    assert json.loads((out / "config.json").read_text())["task"] == "reach2"  # untouched
    (out / "notes.txt").write_text("mine")
    assert main(["train", "throw", "--steps", "100", "--no-progress", "--no-figures", "--force",
                 "--out", str(out)]) == 0
    assert json.loads((out / "config.json").read_text())["task"] == "throw"
    assert not list(out.glob("*.png"))  # no reach2 figure left inside a throw run
    assert (out / "notes.txt").read_text() == "mine"  # what is not a run's file is left alone


def test_reproduce_refuses_an_existing_report_without_force(tmp_path):
    (tmp_path / "REPORT.md").write_text("# an earlier full report\n")
    one_error_line(somarm("reproduce", "--quick", "--only", "reach20", "--out", str(tmp_path)),
                   "is not empty (REPORT.md)", "--force")
    assert (tmp_path / "REPORT.md").read_text() == "# an earlier full report\n"


def test_a_second_signal_does_not_cut_the_final_write_short(tmp_path):
    out = tmp_path / "run"
    proc = _start_training(out)
    try:
        proc.send_signal(signal.SIGINT)
        time.sleep(0.3)  # the run has stopped and is writing (the figures take about a second)
        proc.send_signal(signal.SIGINT)  # a second Ctrl-C, and a SIGTERM
        proc.send_signal(signal.SIGTERM)
        _, err = proc.communicate(timeout=120)
    finally:
        proc.kill()
    assert proc.returncode == 130, err
    assert "Traceback" not in err
    summary = json.loads((out / "summary.json").read_text())
    assert summary["interrupted"] is True and summary["steps"] > 0
    assert {"learner.npz", "config.json", "curves.npz", "learning_curve.png", "input_map.png",
            "action_map.png"} <= {p.name for p in out.iterdir()}
    run.load(out)


def test_reproduce_keeps_the_finished_experiments_when_a_figure_cannot_be_written(tmp_path, monkeypatch):
    from somarm.reproduce import runner
    from somarm.reproduce.report import Section

    def finished(ctx):
        return Section(name="first", title="the first experiment")

    def disk_full(ctx):
        raise ValueError(f"cannot write {ctx.out_dir / 'figures' / 'fig9.png'}: No space left on device")

    monkeypatch.setattr(runner, "EXPERIMENTS", {"first": finished, "second": disk_full})
    with pytest.raises(ValueError, match="fig9.png: No space left on device; second stopped, the report keeps "
                                         r"the 1 experiment\(s\) that finished"):
        runner.reproduce(tmp_path, quick=True, progress=False)
    claims = runner.load_claims(tmp_path)
    assert claims["complete"] is False and list(claims["experiments"]) == ["first"]


def test_a_forced_run_killed_midway_leaves_the_earlier_run_whole(tmp_path):
    out = tmp_path / "run"
    assert somarm("train", "reach2", "--steps", "100", "--no-progress", "--seed", "5", "--out", str(out)).returncode == 0
    (out / "photo.png").write_bytes(b"the user's own picture")
    before = {p.name: p.read_bytes() for p in out.iterdir() if p.is_file() and p.name != ".somarm.lock"}
    proc = _start_training(out, "--force", "--seed", "6")
    proc.kill()  # SIGKILL: no handler runs
    proc.communicate(timeout=60)
    assert {p.name: p.read_bytes() for p in out.iterdir() if p.is_file() and p.name != ".somarm.lock"} == before
    config, _ = run.load(out)
    assert config.seed == 5
    done = somarm("train", "reach2", "--steps", "100", "--no-progress", "--no-figures", "--seed", "7", "--force",
                  "--out", str(out))
    assert done.returncode == 0, done.stderr
    assert run.load(out)[0].seed == 7 and (out / "photo.png").read_bytes() == b"the user's own picture"
    assert not list(out.glob("*_map.png"))  # the earlier run's figures went with it
    assert not [p for p in out.iterdir() if p.name.startswith(".somarm-") and p.name != ".somarm-manifest.json"]


def test_a_forced_reproduction_leaves_the_users_files_in_its_folders(tmp_path):
    out = tmp_path / "report"
    assert somarm("reproduce", "--quick", "--only", "reach20", "--no-progress", "--out", str(out)).returncode == 0
    (out / "figures" / "my_sketch.png").write_bytes(b"mine")
    (out / "notes.md").write_text("mine")
    done = somarm("reproduce", "--quick", "--only", "reach20", "--no-progress", "--force", "--out", str(out))
    assert done.returncode == 0, done.stderr
    assert (out / "figures" / "my_sketch.png").read_bytes() == b"mine" and (out / "notes.md").read_text() == "mine"
    assert (out / "REPORT.md").is_file() and runner_claims(out)["complete"] is True


def runner_claims(out: Path) -> dict:
    return json.loads((out / "claims.json").read_text())


# -- side channels: stdout and stderr that cannot be written ---------------------------------------
def _run_files(out: Path) -> set[str]:
    return {p.name for p in out.iterdir()} & {"learner.npz", "config.json", "curves.npz", "summary.json",
                                              "learning_curve.png"}


@pytest.mark.parametrize("stream", ["stdout", "stderr"])
def test_a_full_device_on_a_standard_stream_costs_nothing(tmp_path, stream):
    out = tmp_path / "run"
    with open("/dev/full", "w") as full:
        done = subprocess.run([sys.executable, "-m", "somarm.cli", "train", "reach2", "--steps", "2000",
                               "--out", str(out)], env=ENV, timeout=120, text=True,
                              **{stream: full, ("stderr" if stream == "stdout" else "stdout"): subprocess.PIPE})
    assert done.returncode == 0, done.stderr or done.stdout
    assert "Traceback" not in (done.stderr or done.stdout or "")
    assert len(_run_files(out)) == 5
    run.load(out)


def test_a_pipe_closed_after_one_line_costs_nothing(tmp_path):
    out = tmp_path / "run"
    proc = subprocess.Popen([sys.executable, "-m", "somarm.cli", "train", "reach2", "--steps", "20000",
                             "--out", str(out)], env=ENV, stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
    proc.stdout.readline()  # as `2>&1 | head -1`: one line read, then the pipe is closed
    proc.stdout.close()
    assert proc.wait(timeout=120) == 0
    assert len(_run_files(out)) == 5
    assert json.loads((out / "summary.json").read_text())["steps"] == 20000


@pytest.mark.parametrize("gl", ["osmesa", "bogus"])
def test_a_mujoco_gl_that_cannot_load_does_not_stop_the_command_line(tmp_path, gl):
    # The command line never renders through MuJoCo; dm_control would refuse these values on import.
    done = subprocess.run([sys.executable, "-m", "somarm.cli", "train", "reach2", "--steps", "100", "--no-progress",
                           "--no-figures", "--out", str(tmp_path / "run")], capture_output=True, text=True,
                          env={**ENV, "MUJOCO_GL": gl}, timeout=120)
    assert done.returncode == 0 and "Traceback" not in done.stderr, done.stderr


def address_space(kib: int):
    """A ``preexec_fn`` that gives the child ``ulimit -v kib``: a small memory, the same on every machine."""
    import resource

    def limited():
        resource.setrlimit(resource.RLIMIT_AS, (kib * 1024, resource.RLIM_INFINITY))

    return limited


def test_an_address_space_limit_is_a_size_check_not_a_traceback(tmp_path):
    done = subprocess.run([sys.executable, "-m", "somarm.cli", "train", "reach2", "--trials", "60000", "--no-progress",
                           "--out", str(tmp_path / "run")], capture_output=True, text=True, env=ENV, timeout=120,
                          preexec_fn=address_space(1_500_000))
    one_error_line(done, "needs about", "of memory, more than the", "available")


def test_reproduce_seeds_that_cannot_fit_are_refused_at_once_and_leave_no_folder(tmp_path):
    out = tmp_path / "report"
    began = time.monotonic()
    done = somarm("reproduce", "--quick", "--seeds", "100000", "--out", str(out), preexec_fn=address_space(2_000_000))
    one_error_line(done, "--seeds 100000 (reach2: ", "needs about", "GiB available; give fewer --seeds")
    assert time.monotonic() - began < 60 and not out.exists()  # no training, no claimed folder, no empty report


def test_reproduce_at_a_few_seeds_still_runs_under_the_same_limit(tmp_path):
    out = tmp_path / "report"
    done = somarm("reproduce", "--quick", "--only", "reach2", "--seeds", "2", "--no-progress", "--out", str(out),
                  preexec_fn=address_space(2_000_000), timeout=300)
    assert done.returncode == 0, done.stderr
    claims = json.loads((out / "claims.json").read_text())
    assert claims["seeds"] == [0, 1] and claims["complete"] and list(claims["experiments"]) == ["reach2"]


def test_a_sweep_point_that_cannot_fit_is_refused_and_its_folder_not_made(tmp_path):
    out = tmp_path / "sweep"
    done = somarm("sweep", "reach2", "--grid", "input_shape=10,20000x20000", "--steps", "200", "--no-progress",
                  "--out", str(out))
    one_error_line(done, "sweep point input_shape=20000x20000: a somq learner", "of memory, more than the")
    assert not out.exists()


@pytest.mark.parametrize("kind", ["U", "complex"])
def test_a_learned_state_of_text_or_complex_numbers_is_a_damaged_file(run_folder, tmp_path, kind):
    bad = _copy_run(run_folder, tmp_path / kind)
    with np.load(run_folder / "learner.npz", allow_pickle=False) as data:
        arrays = {name: data[name] for name in data.files}
    arrays["q"] = arrays["q"].astype(str) if kind == "U" else arrays["q"] + 1j
    np.savez_compressed(bad / "learner.npz", **arrays)
    one_error_line(somarm("evaluate", str(bad)), str(bad / "learner.npz"), "q must hold real numbers")


def test_stdout_closed_or_full_for_a_command_whose_output_is_its_result_is_one_line(tmp_path):
    with open("/dev/full", "w") as full:
        done = subprocess.run([sys.executable, "-m", "somarm.cli", "tasks"], stdout=full, stderr=subprocess.PIPE,
                              text=True, env=ENV, timeout=60)
    one_error_line(done, "cannot write the output to stdout: No space left on device")
    done = subprocess.run([sys.executable, "-m", "somarm.cli", "train", "reach2", "--steps", "100", "--out",
                           str(tmp_path / "run")], stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, env=ENV,
                          timeout=120, text=True, pass_fds=(), close_fds=True, preexec_fn=lambda: os.close(2))
    assert done.returncode == 0 and (tmp_path / "run" / "summary.json").is_file()


def test_out_of_memory_anywhere_is_one_line(tmp_path):
    import resource

    def limited():
        resource.setrlimit(resource.RLIMIT_AS, (1_500_000 * 1024, resource.RLIM_INFINITY))

    done = subprocess.run([sys.executable, "-m", "somarm.cli", "bench", "learner", "--quick", "--trials", "99999999"],
                          capture_output=True, text=True, env=ENV, timeout=120, preexec_fn=limited)
    assert done.returncode == 2 and "Traceback" not in done.stderr, done.stderr
    assert len(done.stderr.strip().splitlines()) == 1, done.stderr
