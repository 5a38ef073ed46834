import json
import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

from somarm.cli import main


def _one_line_error(capsys, code, expected):
    err = capsys.readouterr().err.strip()
    assert code == 2
    assert err.startswith("somarm: error:") and expected in err
    assert "Traceback" not in err and len(err.splitlines()) == 1


def test_tasks_lists_every_task(capsys):
    assert main(["tasks"]) == 0
    out = capsys.readouterr().out
    for name in ("reach2", "reach20", "four_goals", "throw", "throw_distance", "throw_mass"):
        assert name in out


def test_presets_lists_tables(capsys):
    assert main(["presets"]) == 0
    assert "table1" in capsys.readouterr().out


def test_train_writes_a_rerunnable_run(tmp_path, capsys):
    args = ["train", "throw", "--steps", "300", "--trials", "2", "--seed", "5", "--no-progress"]
    assert main([*args, "--out", str(tmp_path / "a")]) == 0
    assert main([*args, "--out", str(tmp_path / "b")]) == 0
    for name in ("config.json", "summary.json", "curves.npz", "learner.npz", "learning_curve.png"):
        assert (tmp_path / "a" / name).is_file()
    config = json.loads((tmp_path / "a" / "config.json").read_text())
    assert config["seed"] == 5 and config["task"] == "throw" and config["n_steps"] == 300
    a = np.load(tmp_path / "a" / "curves.npz")["block_means"]
    b = np.load(tmp_path / "b" / "curves.npz")["block_means"]
    np.testing.assert_array_equal(a, b)
    summary = json.loads((tmp_path / "a" / "summary.json").read_text())
    assert summary["steps"] == 300 and summary["seed"] == 5 and "final_sd_reward" in summary
    capsys.readouterr()
    assert main(["evaluate", str(tmp_path / "a")]) == 0
    assert "greedy mean reward" in capsys.readouterr().out


@pytest.mark.parametrize(
    "args, expected",
    [
        (["train", "nope"], "unknown task"),
        (["train", "reach2", "--preset", "table99"], "table99"),
        (["train", "reach2", "--set", "bogus=1"], "bogus"),
        (["train", "reach2", "--set", "alpha=-1"], "alpha"),
        (["train", "reach2", "--set", "noequals"], "KEY=VALUE"),
        (["train", "reach2", "--trials", "0"], "trials"),
        (["train", "reach2", "--out", "/proc/somarm-cannot-write"], "not writable"),
        (["evaluate", "/nonexistent-run"], "/nonexistent-run does not exist; give a run folder"),
        (["reproduce", "--only", "fig99"], "unknown experiment"),
        (["train", "reach2", "--set", "lambda_a=3"], "learning rate"),
        (["train", "reach2", "--trial-ids", "3", "3"], "differ"),
        (["train", "reach2", "--trials", "5", "--trial-ids", "7"], "disagrees"),
        (["train", "reach2", "--trial-ids", "-1"], "--trial-ids must be a whole number >= 0"),
        (["train", "reach2", "--trials", "0"], "--trials must be a whole number >= 1"),
        (["train", "reach2", "--steps", "0"], "--steps must"),
        (["train", "reach2", "--out", ""], "--out needs a folder name"),
        (["reproduce", "--out", " "], "--out needs a folder name"),
        (["train", "reach2", "--set", "epsilon=1e308"], "epsilon=1e+308 is too large"),
        (["train", "reach2", "--set", "input_shape=20000x20000"], "input_shape=20000x20000, action_shape=50 and 1 "
                                                                 "trial(s), over 50000 steps needs about 160.9 GiB"),
        (["train", "reach2", "--view", "--port", "70000"], "--port must be in 0..65535"),
        (["evaluate", "/nonexistent-run", "--observations", "0"], "--observations must"),
        (["bench", "learner", "--steps", "-5"], "--steps must be a whole number >= 1"),
        (["bench", "learner", "--trials", "1,x"], "--trials takes comma-separated whole numbers"),
        (["bench", "tasks", "--threads", "0"], "--threads must be a whole number >= 1"),
        (["bench", "viewer", "--rate", "0"], "--rate must be > 0"),
        (["view", "juggle"], "unknown task 'juggle'"),
        (["view", "reach2", "--bogus"], "unrecognized arguments: --bogus"),
        (["view", "reach2", "--goals", "100000"], "--goals must be at most 200"),
        (["view", "reach2", "--html", "."], "--html takes a file name, got a folder"),
        (["train", "reach2", "--steps", "50", "--block", "100"], "--block 100 is more than --steps 50"),
        (["train", "reach2", "--steps", "150", "--block", "100"],
         "--steps 150 is not a whole number of --block 100: the last 50 steps would be left out"),
    ],
)
def test_bad_input_is_one_clear_line(args, expected, capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    code = main(args)
    captured = capsys.readouterr()
    err = captured.err.strip()
    assert code == 2 and err.startswith("somarm: error: ") and expected in err, err
    assert "Traceback" not in err and len(err.splitlines()) == 1
    assert captured.out == ""  # refused before any output (a table header)
    assert list(tmp_path.iterdir()) == []  # and before any folder was made


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
def test_a_signal_mid_run_leaves_a_valid_partial_run(tmp_path, sig):
    out = tmp_path / "run"
    proc = subprocess.Popen(
        [sys.executable, "-m", "somarm.cli", "train", "reach2", "--steps", "50000000", "--out", str(out)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env={**os.environ, "MUJOCO_GL": "disable"},
    )
    try:
        deadline = time.monotonic() + 60
        line = ""
        while "mean reward" not in line and time.monotonic() < deadline:  # training has started
            line = proc.stderr.readline()  # away from a terminal the progress bar writes whole lines
        proc.send_signal(sig)
        _, err = proc.communicate(timeout=60)
    finally:
        proc.kill()
    assert proc.returncode == 130, err
    assert "partial results written" in err
    summary = json.loads((out / "summary.json").read_text())
    assert summary["interrupted"] is True and 0 < summary["steps"] < 50_000_000
    assert main(["evaluate", str(out)]) == 0
    assert not list(out.glob("*.tmp"))


@pytest.mark.parametrize(
    "config_text, learner_bytes, expected",
    [
        ("[1, 2]", None, "JSON object"),
        ('{"task": "reach2", "task_params": []}', None, "task_params"),
        ('{"task": "reach2"', None, "not readable JSON"),
        ('{"task": "throw"}', b"PK\x03\x04 truncated", "cannot read a learner"),
    ],
)
def test_damaged_run_folder_is_one_clear_line(tmp_path, capsys, config_text, learner_bytes, expected):
    assert (
        main(["train", "throw", "--steps", "200", "--no-progress", "--no-figures", "--out", str(tmp_path)])
        == 0
    )
    (tmp_path / "config.json").write_text(config_text)
    if learner_bytes is not None:
        (tmp_path / "learner.npz").write_bytes(learner_bytes)
    capsys.readouterr()
    _one_line_error(capsys, main(["evaluate", str(tmp_path)]), expected)


def test_bad_input_leaves_no_output_folder(tmp_path, capsys):
    assert main(["train", "reach2", "--set", "bogus=1", "--out", str(tmp_path / "a")]) == 2
    assert main(["reproduce", "--only", "fig99", "--out", str(tmp_path / "b")]) == 2
    assert not (tmp_path / "a").exists() and not (tmp_path / "b").exists()


def test_a_run_stopped_before_one_block_writes_valid_json(tmp_path):
    # --steps shorter than a --block is refused; a run stopped inside its first block is not.
    from somarm import run

    def stop_at_50(step, observations, actions, rewards):
        if step == 50:
            raise KeyboardInterrupt

    result = run.train(run.RunConfig(task="reach2", n_steps=200), progress=False, on_step=stop_at_50)
    run.write(result, tmp_path, extra_summary=run.greedy_summary(result))

    def no_nan(constant):
        raise AssertionError(f"summary.json holds {constant}, which is not JSON")

    summary = json.loads((tmp_path / "summary.json").read_text(), parse_constant=no_nan)
    assert summary["final_mean_reward"] is None and summary["final_window_steps"] == 0


@pytest.mark.parametrize("argv, flag", [
    (["train", "reach2", "--step", "10"], "--step"),
    (["compare", "reach2", "--sample", "10"], "--sample"),
    (["sweep", "reach2", "--grid", "alpha=0.5", "--step", "10"], "--step"),
    (["bench", "learner", "--trial", "3"], "--trial"),
])
def test_an_abbreviated_option_is_refused_not_expanded(argv, flag, capsys):
    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "unrecognized arguments" in err[0] and flag in err[0], err


@pytest.mark.parametrize("argv, needle", [
    (["train", "reach2", "--steps", "1_000"], "argument --steps: it must be a whole number written with the digits 0-9"),
    (["train", "reach2", "--steps", "\uff11\uff10"], "argument --steps: it must be a whole number"),
    (["train", "reach2", "--set", "alpha=0_1"], "alpha must be a number written with the digits 0-9"),
    (["train", "reach2", "--set", "input_shape=\uff15x5"], "input_shape must look like 50 or 10x10"),
    (["train", "reach2", "--set", "decay=inv:1_000"], "bad decay 'inv:1_000'"),
    (["train", "reach2", "--set", "alpha=0.5", "--set", "alpha=0.7"], "--set alpha is given twice (0.5 and 0.7)"),
    (["train", "reach2", "--task-set", "radius=0.2", "--task-set", "radius=0.3"], "--task-set radius is given twice"),
    (["train", "reach2", "--port", "8000"], "--host and --port are the viewer's: give --view"),
    (["train", "reach2", "--host", "0.0.0.0"], "--host and --port are the viewer's: give --view"),
    (["view", "reach2", "--trial", "3", "--html", "x.html"], "--trial picks a trial of a trained run: give --run"),
    (["presets", "table9"], "unknown preset 'table9'; allowed: table1,"),
    (["sweep", "reach2", "--grid", "alpha=0.5,1", "--trial-ids", "3"], "unrecognized arguments: --trial-ids"),
])
def test_numbers_keys_and_options_that_cannot_mean_what_was_typed_are_one_line(argv, needle, capsys, tmp_path,
                                                                               monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("somarm: error: ") and needle in err[0], err
    assert not (tmp_path / "runs").exists()


def test_sweep_help_lists_no_option_it_refuses(capsys):
    with pytest.raises(SystemExit):
        main(["sweep", "--help"])
    assert "--trial-ids" not in capsys.readouterr().out


def test_presets_name_prints_settings_that_rebuild_the_preset(capsys):
    from somarm.learners import presets
    from somarm.learners.somq import SOMQConfig

    assert main(["presets", "table2"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].startswith("# table2: Table 2")
    texts = dict(line.removeprefix("--set ").split("=", 1) for line in lines[1:])
    assert SOMQConfig().with_overrides(texts) == presets.get("table2")


def test_evaluate_scores_with_the_runs_seed_unless_told(tmp_path, capsys):
    out = tmp_path / "run"
    assert main(["train", "reach2", "--steps", "300", "--trials", "2", "--seed", "5", "--no-progress",
                 "--no-figures", "--out", str(out)]) == 0
    summary = json.loads((out / "summary.json").read_text())
    capsys.readouterr()
    assert main(["evaluate", str(out)]) == 0
    said = capsys.readouterr().out
    assert f"greedy mean reward {summary['greedy_mean_reward']:+.4f}" in said and "seed 5)" in said
    assert main(["evaluate", str(out), "--seed", "0"]) == 0
    assert "seed 0)" in capsys.readouterr().out
    assert main(["evaluate", str(out), "--observations", "10000000000"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--observations 10000000000 for 2 trial(s) needs about" in err[0], err


def test_evaluate_task_set_replays_a_kinematic_run_through_the_servos(tmp_path, capsys):
    from somarm import run, tasks
    from somarm.run import evaluation

    out = tmp_path / "run"
    assert main(["train", "reach2", "--steps", "300", "--trials", "2", "--seed", "3", "--no-progress",
                 "--no-figures", "--out", str(out)]) == 0
    capsys.readouterr()
    assert main(["evaluate", str(out), "--task-set", "dynamics=actuated"]) == 0
    said = capsys.readouterr().out
    # The same number as scoring the loaded learner on the actuated task by hand, and not the kinematic one.
    config, learner = run.load(out)
    actuated = tasks.make("reach2", n_trials=2, seed=3, dynamics="actuated")
    expected = evaluation.evaluate_greedy(learner, actuated, seed=3).mean()
    kinematic = json.loads((out / "summary.json").read_text())["greedy_mean_reward"]
    assert said.startswith("reach2 dynamics=actuated: greedy mean reward") and f"{expected:+.4f}" in said, said
    assert abs(expected - kinematic) > 1e-3
    assert main(["evaluate", str(out), "--task-set", "dynamics=actuated", "--task-set", "settle_time=1"]) == 0
    assert "reach2 dynamics=actuated settle_time=1:" in capsys.readouterr().out


@pytest.mark.parametrize("task_set, expected", [
    (["bogus=1"], "unknown parameter(s) bogus for task reach2; its parameters: centre_x"),
    (["dynamics=torque"], "dynamics must be one of kinematic, actuated, got 'torque'"),
    (["settle_time=soon"], "task parameter settle_time of reach2 takes a number"),
    (["radius"], "--task-set takes KEY=VALUE, got 'radius'"),
    (["radius=0.1", "radius=0.2"], "--task-set radius is given twice"),
    (["radius=0.4"], "the goal circle must lie within the arm's reach"),
])
def test_evaluate_refuses_a_bad_task_set_in_one_line(tmp_path, capsys, task_set, expected):
    out = tmp_path / "run"
    assert main(["train", "reach2", "--steps", "100", "--no-progress", "--no-figures", "--out", str(out)]) == 0
    capsys.readouterr()
    args = [item for value in task_set for item in ("--task-set", value)]
    _one_line_error(capsys, main(["evaluate", str(out), *args]), expected)


def test_evaluate_refuses_a_task_set_that_changes_the_learners_bounds(tmp_path, capsys):
    out = tmp_path / "run"
    assert main(["train", "reach2_obstacle", "--steps", "100", "--block", "50", "--no-progress", "--no-figures",
                 "--out", str(out)]) == 0
    capsys.readouterr()
    _one_line_error(capsys, main(["evaluate", str(out), "--task-set", "max_step=0.2"]),
                    "--task-set max_step=0.2 changes the task's action bounds from those the learner was trained on")


def test_an_episodic_run_reports_its_greedy_return_not_a_one_step_reward(tmp_path, capsys):
    out = tmp_path / "run"
    assert main(["train", "reach2_obstacle", "--steps", "200", "--trials", "2", "--no-progress", "--no-figures",
                 "--out", str(out)]) == 0
    trained = capsys.readouterr().out
    summary = json.loads((out / "summary.json").read_text())
    assert {"greedy_mean_return", "greedy_sd_return", "greedy_success_rate", "greedy_mean_episode_length",
            "shortest_mean_episode_length"} <= set(summary)
    # The shortest paths from the same starts: a few steps around the wall, never more than the greedy episodes.
    assert 2 <= summary["shortest_mean_episode_length"] <= summary["greedy_mean_episode_length"]
    assert "greedy_mean_reward" not in summary and "greedy_sd_reward" not in summary
    # Every step pays at most -1, and a failed episode counts at the 20-step limit.
    assert summary["greedy_mean_return"] <= -summary["greedy_mean_episode_length"] < 0
    assert 1 <= summary["greedy_mean_episode_length"] <= 20
    if summary["greedy_success_rate"] == 0:
        assert summary["greedy_mean_episode_length"] == 20
    assert f"greedy mean return {summary['greedy_mean_return']:+.4f}" in trained
    assert main(["evaluate", str(out)]) == 0
    said = capsys.readouterr().out
    assert f"greedy mean return {summary['greedy_mean_return']:+.4f}" in said, said
    assert f"success rate {summary['greedy_success_rate']:.1%}" in said and "reward" not in said
    assert f"the shortest paths {summary['shortest_mean_episode_length']:.2f}" in said


def test_reproduce_and_compare_take_a_first_seed(tmp_path):
    from somarm.reproduce import runner

    assert main(["reproduce", "--quick", "--only", "reach20", "--seed", "3", "--no-progress",
                 "--out", str(tmp_path / "r")]) == 0
    claims = runner.load_claims(tmp_path / "r")
    assert claims["seed"] == 3 and claims["seeds"] == [3]
    assert main(["compare", "reach2", "--learners", "somq", "--samples", "100", "--seeds", "2", "--seed", "4",
                 "--observations", "50", "--no-progress", "--out", str(tmp_path / "c")]) == 0
    assert json.loads((tmp_path / "c" / "compare.json").read_text())["seeds"] == [4, 5]


@pytest.mark.parametrize("argv, needle", [
    (["train", "reach2", "--steps", "100", "--steps", "200"], "--steps is given twice; give it once"),
    (["sweep", "reach2", "--grid", "alpha=0.5,1", "--seeds", "2", "--seeds=3"], "--seeds is given twice"),
    (["train", "throw", "--task-set", "punish_low=maybe"], "punish_low of throw takes true or false, got the text"),
    (["train", "four_goals", "--task-set", "goals_before=x"], "goals_before of four_goals takes a JSON list"),
])
def test_a_value_given_twice_or_in_the_wrong_form_is_named_with_what_is_allowed(argv, needle, capsys):
    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and needle in err[0], err


def test_evaluate_of_a_folder_being_written_names_the_writer(tmp_path, capsys):
    from somarm.run.claim import claim

    held = claim(tmp_path / "run")
    try:
        assert main(["evaluate", str(tmp_path / "run")]) == 2
        err = capsys.readouterr().err
        assert f"is being written by a somarm process (pid {os.getpid()})" in err, err
    finally:
        held.release()


@pytest.mark.parametrize("field, value", [("overrides", [("epsilon", 0.2)]), ("task_params", None),
                                          ("task_params", "radius=0.2"), ("trial_ids", 5)])
def test_the_python_api_refuses_a_setting_of_the_wrong_type_in_one_line(field, value):
    from somarm import run

    with pytest.raises(ValueError, match=f"^{field} must be a"):
        run.RunConfig(task="reach2", **{field: value}).resolved()


@pytest.mark.parametrize(("argv", "unwanted"), [
    ([], ("numba", "mujoco", "dm_control", "matplotlib", "torch", "gymnasium", "ray")),
    (["--help"], ("numba", "mujoco", "dm_control", "matplotlib", "torch", "gymnasium", "ray")),
    (["presets"], ("mujoco", "dm_control", "matplotlib", "torch", "gymnasium", "ray")),
    (["tasks"], ("matplotlib", "torch", "gymnasium", "ray", "somarm.run", "somarm.sweep")),
])
def test_listing_commands_import_only_what_they_need(argv, unwanted):
    # What the listings answer from, and nothing else: the run machinery, the plots and the extras load
    # only for the commands that use them (their time is scripts/bench_startup.py's to measure).
    code = ("import sys, contextlib, io\nfrom somarm.cli import main\n"
            "with contextlib.redirect_stdout(io.StringIO()):\n"
            "    try:\n        main(sys.argv[1:])\n    except SystemExit:\n        pass\n"
            f"print(' '.join(m for m in {unwanted!r} if m in sys.modules))")
    done = subprocess.run([sys.executable, "-c", code, *argv], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0 and done.stdout.strip() == "", done.stdout + done.stderr


def test_the_full_parser_and_the_one_a_command_builds_agree():
    from somarm.cli import _parser

    full, own = _parser(), _parser(["train"])
    train = full._subparsers._group_actions[0].choices["train"]._actions
    assert [a.dest for a in train] == [a.dest for a in own._subparsers._group_actions[0].choices["train"]._actions]
    assert {"task", "learner", "seed", "n_trials", "n_steps"} <= {a.dest for a in train}  # the run settings


@pytest.mark.parametrize(("argv", "expected"), [
    (["compare", "reach2", "--ray-address", "10.0.0.1:6379"], "--ray-address is for --engine ray: give both, or neither"),
    (["reproduce", "--quick", "--ray-address", "10.0.0.1:6379"], "--ray-address is for --engine ray"),
    (["compare", "reach2", "--engine", "ray", "--ray-address", " "], "--ray-address needs an address (HOST:PORT"),
    (["reproduce", "--engine", "spark"], "argument --engine: invalid choice: 'spark'"),
])
def test_engine_options_are_checked_before_anything_is_written(argv, expected, capsys, tmp_path):
    _one_line_error(capsys, main([*argv, "--out", str(tmp_path / "x")]), expected)
    assert not (tmp_path / "x").exists()


def test_engine_ray_without_ray_names_the_extra_in_one_line(capsys, tmp_path, monkeypatch):
    import importlib.util

    real = importlib.util.find_spec
    monkeypatch.setattr(importlib.util, "find_spec", lambda name, *a: None if name == "ray" else real(name, *a))
    _one_line_error(capsys, main(["compare", "reach2", "--engine", "ray", "--out", str(tmp_path / "x")]),
                    "--engine ray needs Ray")
    assert not (tmp_path / "x").exists()
    with pytest.raises(ImportError, match=r"\[sweep\]"):  # from Python: an ImportError, as for any missing extra
        from somarm import cluster

        cluster.check_engine("ray", None)


def test_somarm_alone_prints_its_usage_and_every_command(capsys):
    from somarm.cli import _parser

    assert main([]) == 0
    shown = capsys.readouterr()
    commands = _parser([])._subparsers._group_actions[0].choices
    assert shown.out.startswith("usage: somarm") and shown.err == ""
    assert all(f"\n    {name} " in shown.out or f"\n    {name}\n" in shown.out for name in commands), shown.out


def test_version_prints_the_packages_version(capsys):
    import somarm

    with pytest.raises(SystemExit) as exit_:
        main(["--version"])
    assert exit_.value.code == 0
    assert capsys.readouterr().out.strip() == f"somarm {somarm.__version__}"


def _every_help():
    from somarm.cli import _parser

    yield []
    from somarm.cli import _BENCHMARKS

    yield from ([name] for name in _parser()._subparsers._group_actions[0].choices if name != "bench")
    yield ["view"]
    yield from (["bench", name] for name in _BENCHMARKS)


@pytest.mark.parametrize("argv", list(_every_help()), ids=lambda argv: " ".join(argv) or "somarm")
def test_help_is_plain_text_without_backticks(argv, capsys):
    with pytest.raises(SystemExit):
        main([*argv, "--help"])
    shown = capsys.readouterr().out
    assert shown.startswith("usage:") and "`" not in shown, shown


def test_a_gym_run_folder_has_no_colon_and_an_old_one_is_still_read(tmp_path, capsys, monkeypatch):
    pytest.importorskip("gymnasium")
    monkeypatch.chdir(tmp_path)
    args = ["train", "gym:Pendulum-v1", "--steps", "200", "--block", "100", "--no-progress", "--no-figures",
            "--task-set", "evaluation_steps=5"]
    assert main(args) == 0
    assert [p.name for p in (tmp_path / "runs").iterdir()] == ["gym-Pendulum-v1__somq__seed0"]
    old = tmp_path / "runs" / "gym:Pendulum-v1__somq__seed0"  # the name earlier versions gave it
    (tmp_path / "runs" / "gym-Pendulum-v1__somq__seed0").rename(old)
    capsys.readouterr()
    assert main(["evaluate", str(old)]) == 0
    said = capsys.readouterr().out
    assert said.startswith("gym:Pendulum-v1: greedy mean return")
    # Pendulum's episodes have no goal and cannot fail: the length is not said to count failures
    assert "failed episode" not in said, said



def test_compare_plans_the_comparison_once(tmp_path, monkeypatch):
    from somarm.peers import compare

    made = []
    real = compare.make_plan
    monkeypatch.setattr(compare, "make_plan", lambda config: made.append(config) or real(config))
    assert main(["compare", "reach2", "--learners", "somq", "--samples", "100", "--seeds", "1", "--no-progress",
                 "--out", str(tmp_path / "c")]) == 0
    assert len(made) == 1


def test_python_dash_m_somarm_is_the_somarm_command():
    import somarm

    done = subprocess.run([sys.executable, "-m", "somarm", "--version"], capture_output=True, text=True, timeout=60)
    assert done.returncode == 0 and done.stdout.strip() == f"somarm {somarm.__version__}", done.stderr


def test_the_entry_point_imports_nothing_heavy_before_main_guards_ctrl_c():
    # Ctrl-C while numpy loads must end in "somarm: interrupted", which only main() can print: so the
    # module the console script imports first loads the standard library and somarm's light modules only.
    code = "import sys, somarm.cli; print(' '.join(sorted(m for m in sys.modules if m.split('.')[0] in " \
           "('numpy', 'somarm') and m not in ('somarm', 'somarm.cli', 'somarm.console', 'somarm.helptext'))))"
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert done.returncode == 0 and done.stdout.strip() == "", done.stdout + done.stderr


def test_a_run_shorter_than_its_tasks_default_says_so_and_a_full_one_does_not(tmp_path, capsys):
    from somarm import tasks

    default = tasks.record("throw").n_steps
    for steps, said in ((default // 10, True), (default, False)):
        assert main(["train", "throw", "--steps", str(steps), "--no-progress", "--no-figures",
                     "--out", str(tmp_path / str(steps))]) == 0
        done = capsys.readouterr().out
        assert (f"default run is {default:,} steps" in done) is said, done
