"""``somarm sweep`` on the local engine: specs, lockstep equals separate runs, resume, failures."""

import csv
import json
import signal

import numpy as np
import pytest

from somarm import cli, learners, run
from somarm.run import group
from somarm.sweep import SweepSpec, parse_grid, parse_random, run_sweep
from somarm.sweep.spec import preset_value
from somarm.sweep.work import plan_chunks

TINY = ["--trials", "2", "--steps", "200", "--block", "50", "--no-progress"]


def read_csv(path):
    with open(path) as handle:
        return list(csv.DictReader(handle))


@pytest.mark.parametrize(
    "options",
    [
        ["--grid", "alpha"],
        ["--grid", "alpha="],
        ["--grid", "alpha=0.5,,1"],
        ["--grid", "alpha=0.5,0.5"],
        ["--grid", "=0.5,1"],
        ["--grid", "alfa=0.5,1"],
        ["--grid", "alpha=0.5,2"],
        ["--grid", "task.radius=0.25,0.9"],
        ["--grid", "task.nope=1,2"],
        ["--grid", "alpha=0.5,1", "--grid", "alpha=0.1,0.2"],
        ["--grid", "alpha=0.5,1", "--set", "alpha=0.3"],
        ["--random", "alpha=0.1", "--samples", "2"],
        ["--random", "alpha=0.9:0.1", "--samples", "2"],
        ["--random", "alpha=0:1:log", "--samples", "2"],
        ["--random", "alpha=0.1:1:lin", "--samples", "2"],
        ["--random", "alpha=0.1:1"],
        ["--grid", "alpha=0.5,1", "--samples", "3"],
        ["--grid", "alpha=0.5,1", "--seeds", "0"],
        ["--grid", "alpha=0.5,1", "--engine", "dask"],
        ["--grid", "alpha=0.5,1", "--address", "127.0.0.1:6379"],
        ["--grid", "alpha=0.5,1", "--trial-ids", "3"],
        [],
    ],
)
def test_a_bad_sweep_spec_ends_in_one_line_before_anything_is_written(options, tmp_path, capsys):
    out = tmp_path / "sweep"
    assert cli.main(["sweep", "reach2", *options, "--out", str(out), *TINY]) == 2
    err = capsys.readouterr().err
    assert err.startswith("somarm: error: ") and err.count("\n") == 1, err
    assert not out.exists()


def test_grid_and_random_axes_give_every_combination_with_reproducible_draws():
    spec = SweepSpec(
        task="reach2",
        axes=(parse_grid("decay=inv:500,inv:1000"), parse_random("alpha=0.1:1:log"), parse_random("task.radius=1:3")),
        n_samples=3,
    )
    points = spec.points()
    assert len(points) == 6 and points == spec.points()  # 2 grid values x 3 draws, the same each time
    assert [p["decay"] for p in points] == ["inv:500"] * 3 + ["inv:1000"] * 3
    alphas = np.array([float(p["alpha"]) for p in points])
    assert ((alphas >= 0.1) & (alphas <= 1)).all() and len(set(alphas[:3])) == 3
    assert all(p["task.radius"] in ("1", "2", "3") for p in points)  # whole-number bounds draw whole numbers
    assert preset_value(spec.check(), "decay") == "inv:1000" and preset_value(spec.check(), "alpha") == "1"
    assert preset_value(spec.check(), "task.radius") == "0.25"


def test_points_sharing_a_task_and_seed_train_in_one_group_cut_only_for_memory():
    spec = SweepSpec(task="reach2", axes=(parse_grid("alpha=0.5,1"), parse_grid("task.radius=0.2,0.25")),
                     n_seeds=2).check()
    items = [(i, s, spec.config(p, s)) for i, p in enumerate(spec.points()) for s in range(2)]
    chunks = plan_chunks(items)
    assert len(chunks) == 4  # 2 task parameter sets x 2 seeds, each with both alphas
    for chunk in chunks:
        assert len({(c.seed, c.task_params["radius"]) for _, _, c in chunk.items}) == 1
        assert sorted(c.overrides["alpha"] for _, _, c in chunk.items) == [0.5, 1.0]
    assert len(plan_chunks(items, max_bytes=1.0)) == 8  # too big for one group: one point each


@pytest.mark.parametrize("kind", learners.LEARNERS)
def test_chunks_are_cut_by_each_learner_kinds_own_memory_estimate(kind):
    from somarm.run import RunConfig

    config = RunConfig(task="reach2", learner=kind).resolved()
    items = [(0, 0, config), (1, 0, config)]
    assert len(plan_chunks(items)) == 1 and len(plan_chunks(items, max_bytes=1.0)) == 2


def test_a_local_sweep_equals_separate_runs_bit_for_bit(tmp_path, capsys):
    out = tmp_path / "sweep"
    argv = ["sweep", "reach2", "--grid", "alpha=0.5,1", "--grid", "task.radius=0.2,0.25", "--seeds", "2"]
    assert cli.main([*argv, "--out", str(out), *TINY]) == 0
    summary = capsys.readouterr().out
    rows = read_csv(out / "results.csv")
    assert len(rows) == 8 and {"alpha", "task.radius", "seed", "greedy_error", "final_error"} <= set(rows[0])
    best = json.loads((out / "best.json").read_text())
    assert f"best alpha={best['values']['alpha']} task.radius={best['values']['task.radius']}" in summary
    assert "preset table1 has alpha=1" in summary and "task.radius=0.25" in summary.split("preset")[1]
    for row in (rows[1], rows[6]):  # one point of each task and seed, run alone through `somarm train`
        run = tmp_path / f"run{row['point']}_{row['seed']}"
        train = ["train", "reach2", "--set", f"alpha={row['alpha']}", "--task-set", f"radius={row['task.radius']}",
                 "--seed", row["seed"], "--out", str(run), "--no-figures", *TINY]
        assert cli.main(train) == 0
        alone = json.loads((run / "summary.json").read_text())
        assert -float(row["greedy_error"]) == alone["greedy_mean_reward"]
        assert -float(row["final_error"]) == alone["final_mean_reward"]
    # best.json's command reruns the best point as it was swept
    command = best["command"].split()
    assert command[:3] == ["somarm", "train", "reach2"] and f"alpha={best['values']['alpha']}" in command


def test_a_sweep_of_an_episodic_task_ranks_by_the_greedy_return(tmp_path, capsys):
    out = tmp_path / "sweep"
    argv = ["sweep", "reach2_obstacle", "--grid", "gamma=0,0.9", "--trials", "1", "--steps", "200", "--block", "50",
            "--no-progress", "--out", str(out)]
    assert cli.main(argv) == 0
    said = capsys.readouterr().out
    rows = read_csv(out / "results.csv")
    assert "greedy cost (minus the episode return)" in said
    run_out = tmp_path / "alone"  # the gamma 0 point, run alone through `somarm train`
    assert cli.main(["train", "reach2_obstacle", "--set", "gamma=0", "--trials", "1", "--steps", "200",
                     "--block", "50", "--no-progress", "--no-figures", "--out", str(run_out)]) == 0
    alone = json.loads((run_out / "summary.json").read_text())
    row = next(r for r in rows if float(r["gamma"]) == 0)
    assert -float(row["greedy_error"]) == alone["greedy_mean_return"]
    best = json.loads((out / "best.json").read_text())
    highest = max(rows, key=lambda r: -float(r["greedy_error"]))  # the highest mean return
    assert float(best["values"]["gamma"]) == float(highest["gamma"])


def test_an_interrupted_sweep_keeps_its_rows_and_a_rerun_finishes_only_the_rest(tmp_path, monkeypatch):
    spec = SweepSpec(task="reach2", axes=(parse_grid("alpha=0.5,1"),), n_trials=2, n_steps=200, block=50,
                     n_seeds=3)
    real = run.train_group
    calls = []

    def ctrl_c_in_second_group(configs, **kwargs):
        calls.append(len(configs))

        def hook(step, *arrays):
            if len(calls) == 2 and step == 20:
                signal.raise_signal(signal.SIGINT)  # as Ctrl-C: the run stops after this step

        return real(configs, **{**kwargs, "on_step": hook})

    monkeypatch.setattr(run, "train_group", ctrl_c_in_second_group)
    out = tmp_path / "sweep"
    first = run_sweep(spec, out, progress=False, figure=False)
    assert first.interrupted and calls == [2, 2]
    rows = read_csv(out / "results.csv")
    assert [(r["point"], r["seed"]) for r in rows] == [("0", "0"), ("1", "0")]  # seed 0 only, both complete
    assert "no point finished every seed (2 of 6 runs done)" in first.summary
    assert not (out / "best.json").exists()  # no best until some point has every seed
    kept = {p.name: p.read_bytes() for p in (out / "points").iterdir()}

    second = run_sweep(spec, out, progress=False, figure=False)
    assert not second.interrupted and second.n_run == 4 and calls == [2, 2, 2, 2]  # seeds 1 and 2 only
    assert all((out / "points" / name).read_bytes() == data for name, data in kept.items())
    assert len(read_csv(out / "results.csv")) == 6 and json.loads((out / "best.json").read_text())["seeds"] == 3
    assert run_sweep(spec, out, progress=False, figure=False).n_run == 0


def test_a_failing_point_is_recorded_with_its_error_and_the_others_finish(tmp_path, monkeypatch):
    spec = SweepSpec(task="reach2", axes=(parse_grid("alpha=0.5,0.7,1"),), n_trials=2, n_steps=200, block=50)
    real = run.make_learner

    def broken_for_alpha_07(config, task):
        if config.overrides.get("alpha") == 0.7:
            raise FloatingPointError("the learner diverged")
        return real(config, task)

    monkeypatch.setattr(group, "make_learner", broken_for_alpha_07)  # where RunGroup builds
    out = tmp_path / "sweep"
    outcome = run_sweep(spec, out, progress=False, figure=False)
    rows = {r["alpha"]: r for r in read_csv(out / "results.csv")}
    assert rows["0.7"]["error"] == "FloatingPointError: the learner diverged" and rows["0.7"]["greedy_error"] == ""
    assert all(np.isfinite(float(rows[a]["greedy_error"])) and not rows[a]["error"] for a in ("0.5", "1"))
    assert json.loads((out / "best.json").read_text())["values"]["alpha"] in ("0.5", "1")
    assert not outcome.interrupted and "3 of 3 runs done" in outcome.summary

    monkeypatch.setattr(group, "make_learner", real)
    again = run_sweep(spec, out, progress=False, figure=False)
    assert again.n_run == 1 and not read_csv(out / "results.csv")[1]["error"]  # the failed point is retried


def test_importing_the_sweep_package_loads_neither_ray_nor_matplotlib():
    import subprocess
    import sys

    code = "import sys, somarm.sweep; print(sorted({'ray', 'matplotlib'} & set(sys.modules)))"
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert done.stdout.strip() == "[]"


def test_points_are_typed_run_configs_named_by_their_settings_text():
    import hashlib

    from somarm.learners.schedules import InverseDecay
    from somarm.sweep.spec import config_key

    spec = SweepSpec.around(run.RunConfig(task="reach2", overrides={"gamma": 0.5}, task_params={"radius": 0.2}),
                            (parse_grid("decay=inv:250,inv:500"), parse_grid("task.centre_x=0.5")), n_seeds=1).check()
    config = spec.config(spec.points()[0], 0)
    assert config.overrides == {"gamma": 0.5, "decay": InverseDecay(250.0)}
    assert config.task_params == {"radius": 0.2, "centre_x": 0.5}
    assert config.learner_config.alpha.decay == InverseDecay(250.0) and config.learner_config.gamma == 0.5
    # sweep.json and the tables keep the text form.
    assert spec.to_dict()["overrides"] == {"gamma": "0.5"} and spec.to_dict()["task_params"] == {"radius": "0.2"}
    assert spec.fixed_texts() == {"gamma": "0.5", "task.radius": "0.2"}
    # A point's key is the hash of its settings as text, as sweep folders written before typed settings
    # named it, so a rerun there finds its rows; 1 and 1.0 are one point.
    old_form = {"task": "reach2", "learner": "somq", "preset": "table1", "overrides": {"gamma": "0.5", "decay": "inv:250"},
                "task_params": {"radius": "0.2", "centre_x": "0.5"}, "n_trials": 1, "n_steps": spec.n_steps, "seed": 0,
                "backend": "mujoco", "block": 100, "trial_ids": None}
    assert config_key(config) == hashlib.sha256(json.dumps(old_form, sort_keys=True).encode()).hexdigest()[:16]
    whole = SweepSpec(task="reach2", axes=(parse_grid("alpha=1,1.0"),)).check()
    assert len({config_key(whole.config(point, 0)) for point in whole.points()}) == 1


def test_a_point_that_cannot_fit_in_memory_is_refused_in_one_line_before_the_folder_is_made(tmp_path):
    spec = SweepSpec(task="reach2", axes=(parse_grid("input_shape=10,20000x20000"),), n_trials=2, n_steps=200)
    out = tmp_path / "sweep"
    with pytest.raises(ValueError) as refused:
        run_sweep(spec, out, progress=False, figure=False)
    message = str(refused.value)
    assert message.startswith("sweep point input_shape=20000x20000: a somq learner with input_shape=20000x20000")
    assert "\n" not in message and "of memory, more than the" in message
    assert not out.exists()


def test_a_bad_axis_value_is_named_with_its_point():
    spec = SweepSpec(task="reach2", axes=(parse_grid("alpha=0.5,fast"),)).check()
    with pytest.raises(ValueError, match=r"^alpha=fast: alpha must be a number written with the digits 0-9 .*'fast'$"):
        spec.config(spec.points()[1], 0)


def test_a_chunk_crosses_to_a_worker_as_json_and_comes_back_the_same_configs():
    from somarm.sweep.work import Chunk

    spec = SweepSpec(task="four_goals", axes=(parse_grid("decay=inv:250,exp:0.999"),
                                              parse_grid("task.switch_step=500")), n_steps=1000).check()
    chunk = Chunk(tuple((i, 0, spec.config(p, 0)) for i, p in enumerate(spec.points())))
    back = Chunk.from_dict(json.loads(json.dumps(chunk.to_dict())))
    assert [(i, s, c.resolved()) for i, s, c in back.items] == list(chunk.items)
