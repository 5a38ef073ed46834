"""``somarm compare`` and the reproduce part ``peers``: tiny budgets, every learner (TD3 and SAC too)."""

import json
import sys

import numpy as np
import pytest

from somarm import tasks
from somarm.cli import main
from somarm.peers import compare
from somarm.reproduce import runner

if compare.peers_missing():  # the peers extra (with CI=true, conftest turns this skip into a failure)
    pytest.skip(compare.peers_missing(), allow_module_level=True)


def test_the_ladder_is_1_2_5_below_the_budget_then_the_budget():
    assert compare.ladder(1200) == [100, 200, 500, 1000, 1200]
    assert compare.ladder(1000) == [100, 200, 500, 1000]
    assert compare.ladder(50) == [50]


def test_compare_smoke_every_learner_writes_json_and_png(tmp_path, capsys):
    out = tmp_path / "cmp"
    code = main(["compare", "throw_distance", "--samples", "150", "--peer-samples", "110", "--seeds", "2",
                 "--observations", "50", "--out", str(out), "--no-progress"])
    assert code == 0, capsys.readouterr().err
    result = json.loads((out / "compare.json").read_text())
    assert result["complete"] and result["seeds"] == [0, 1] and sorted(result["learners"]) == sorted(compare.LEARNERS)
    assert 0 < result["random_action_error"] < 10
    for kind, data in result["learners"].items():
        assert data["samples"] == ([100, 110] if kind in compare.PEERS else [100, 150])
        errors, walls = np.array(data["error"]), np.array(data["wall_seconds"])
        assert errors.shape == walls.shape == (2, 2)
        assert np.isfinite(errors).all() and (errors >= 0).all()
        assert (np.diff(walls, axis=0) >= 0).all() and (walls > 0).all()
        assert len(data["seconds_per_sample"]) == 2 and data["settings"]
    assert "learning_rate" in result["learners"]["td3"]["settings"]
    assert result["learners"]["sac"]["settings"]["torch_threads"] == 1
    assert result["learners"]["somq"]["settings"]["input_shape"] == [30]  # table5, the task's preset
    assert (out / "compare.png").stat().st_size > 10_000


def test_the_same_seed_gives_the_same_errors_for_somarm_learners(tmp_path):
    config = compare.CompareConfig(task="reach2", learners=("somq", "tabular"), samples=120, seeds=1,
                                   observations=30)
    first = compare.compare(config, tmp_path / "a", progress=False)
    second = compare.compare(config, tmp_path / "b", progress=False)
    for kind in config.learners:
        assert first["learners"][kind]["error"] == second["learners"][kind]["error"]


@pytest.mark.parametrize(("argv", "message"), [
    (["reach2", "--learners", "somq,ppo"], "unknown learner(s) ppo; allowed: somq, somq+, motoric, tabular, td3, sac"),
    (["reach20", "--learners", "tabular"], "tabular cannot learn reach20"),
    (["reach3"], "unknown task 'reach3'"),
    (["reach2_obstacle"], "reach2_obstacle has multi-step episodes; compare takes gym:ID, dmc:DOMAIN-TASK and the one-step tasks"),
    (["reach2", "--seeds", "0"], "seeds must be a whole number >= 1"),
])
def test_bad_compare_arguments_end_in_one_line(argv, message, capsys, tmp_path):
    assert main(["compare", *argv, "--out", str(tmp_path / "x")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("somarm: error: ") and message in err
    assert not (tmp_path / "x").exists()


def test_without_the_extra_td3_names_the_missing_extra(monkeypatch, capsys, tmp_path):
    monkeypatch.setitem(sys.modules, "stable_baselines3", None)  # import fails as if not installed
    assert main(["compare", "reach2", "--learners", "somq,td3", "--out", str(tmp_path / "x")]) == 2
    err = capsys.readouterr().err
    # The command that works here (an editable clone: its own folder), torch's CPU build first.
    assert "optional extra 'peers'" in err and '[peers]"' in err and err.count("\n") == 1
    assert err.index("download.pytorch.org/whl/cpu") < err.index("[peers]")
    assert main(["reproduce", "--only", "peers", "--out", str(tmp_path / "y")]) == 2
    assert "optional extra 'peers'" in capsys.readouterr().err


def test_the_peers_part_is_optional_and_runs_when_named(tmp_path):
    assert "peers" not in runner.EXPERIMENTS and runner.check_names(["peers"]) == ["peers"]
    assert runner.reproduce(tmp_path, quick=True, only=["peers"], progress=False) == 0
    claims = runner.load_claims(tmp_path)["experiments"]["peers"]["claims"]
    assert len(claims) == 2 and all(c["holds"] in (True, False) for c in claims)
    report = (tmp_path / "REPORT.md").read_text()
    assert ("| samples | SOM-Q | SOM-Q+ (interpolated) | Motoric Map | tabular (fixed grid) | SB3 TD3 | SB3 SAC |"
            in report)
    assert "| learner | error <= 0.05 | error <= 0.02 | error <= 0.01 |" in report
    assert report.count("\n| SB3 TD3 | ") == 3  # a time-to-error row per task
    for task in ("reach2", "reach20", "throw_distance"):
        assert (tmp_path / "peers" / task / "compare.png").stat().st_size > 10_000
        assert f"](peers/{task}/compare.png)" in report


def test_compare_scores_a_gymnasium_environment_by_greedy_returns_with_the_zoos_settings(tmp_path):
    config = compare.CompareConfig(task="gym:Pendulum-v1", learners=("somq", "td3"), samples=300, peer_samples=300,
                                   seeds=1, episodes=5)
    result = compare.compare(config, tmp_path, progress=False)
    assert result["metric"] == "return" and result["episodes"] == 5
    assert -2000 < result["random_action_return"] < -500  # Pendulum's random torques
    for kind in ("somq", "td3"):
        returns = np.array(result["learners"][kind]["return"])
        assert returns.shape == (len(compare.ladder(300)), 1) and np.all((returns < 0) & (returns > -2000))
    td3 = result["learners"]["td3"]["settings"]
    assert td3["source"].startswith("rl-zoo3 ") and "400, 300" in td3["net_arch"] and td3["gamma"] == "0.98"
    assert "NormalActionNoise" in td3["action_noise"]
    assert (tmp_path / "compare.png").stat().st_size > 10_000


def test_the_zoos_entries_become_sb3_keywords_and_other_environments_take_sb3s_defaults():
    from somarm.peers import zoo

    keywords, budget, source = zoo.settings("sac", "MountainCarContinuous-v0", 1)
    assert budget == 50_000 and source.startswith("rl-zoo3")
    assert keywords["use_sde"] is True and keywords["policy_kwargs"]["net_arch"] == [64, 64]
    assert keywords["policy_kwargs"]["log_std_init"] == -3.67 and "n_timesteps" not in keywords
    keywords, budget, source = zoo.settings("td3", "MountainCarContinuous-v0", 1)
    assert budget == 300_000 and type(keywords["action_noise"]).__name__ == "OrnsteinUhlenbeckActionNoise"
    keywords, budget, source = zoo.settings("td3", "InvertedPendulum-v5", 1)
    assert budget is None and source == "SB3 defaults with Gaussian action noise 0.1"
    assert float(keywords["action_noise"]._sigma[0]) == 0.1
    assert zoo.settings("sac", "Reacher-v5", 2)[:2] == ({}, None)
    assert compare.peer_budget("td3", compare.CompareConfig(task="gym:Pendulum-v1")) == 20_000
    assert compare.peer_budget("sac", compare.CompareConfig(task="gym:Reacher-v5", samples=777)) == 777
    # Without --samples, somarm's learners train for a gym:ID's run length, the budget its results use.
    assert compare.default_samples("gym:Pendulum-v1") == tasks.record("gym:Pendulum-v1").n_steps == 500_000
    assert compare.default_samples("reach2") == 10_000


def test_zoo_schedules_are_read_and_what_is_not_applied_is_named():
    """The Zoo's ``lin_X`` learning rates fall linearly to 0; keys that change the environment (here
    observation normalising) are not applied, and the source says which."""
    from somarm.peers import zoo

    keywords, budget, source = zoo.settings("sac", "HumanoidBulletEnv-v0", 17)
    rate = keywords["learning_rate"]
    assert repr(rate) == "lin_0.0003" and rate(1.0) == pytest.approx(3e-4) and rate(0.25) == pytest.approx(7.5e-5)
    assert source.startswith("rl-zoo3 ") and source.endswith(", without its normalize")
    assert "normalize" not in keywords and budget > 0
    assert "without" not in zoo.settings("sac", "MountainCarContinuous-v0", 1)[2]


def test_the_benchmarks_part_is_optional_and_reports_returns_targets_and_the_zoos_numbers(tmp_path):
    from somarm.reproduce import benchmarks

    assert "benchmarks" not in runner.EXPERIMENTS and runner.check_names(["benchmarks"]) == ["benchmarks"]
    # One environment alone, in the folders the whole part uses.
    assert runner.reproduce(tmp_path, quick=True, only=["benchmarks_pendulum"], progress=False) == 0
    claims = runner.load_claims(tmp_path)["experiments"]["benchmarks_pendulum"]["claims"]
    # Each response's target and speed claims; 400 samples swing the pendulum up in neither response.
    assert len(claims) == 4 and claims[0]["holds"] is False and claims[1]["holds"] is False
    report = (tmp_path / "REPORT.md").read_text()
    assert "| environment | learner | final return (mean ± sd) | to the peers' converged return |" in report
    for kind in ("SOM-Q", "SOM-Q+ (interpolated)", "Motoric Map", "tabular (fixed grid)", "SB3 TD3", "SB3 SAC"):
        assert f"| Pendulum-v1 | {kind} | " in report
    assert "TD3 on Pendulum-v1: -152 ± 90 after 20000 steps" in report and "MountainCarContinuous" not in report
    # Its title and header speak of Gymnasium's environments, not of the paper's arms.
    assert report.startswith("# somarm: SOM-Q on Gymnasium's benchmarks beside TD3 and SAC\n")
    assert "every return from Gymnasium's own environment" in report and "Arm lengths" not in report
    assert "Wall time of this run" in report and "the paper ran no Gymnasium environment" in report
    merged = json.loads((tmp_path / "benchmarks" / "Pendulum-v1" / "compare.json").read_text())
    assert set(merged["learners"]) == set(benchmarks.LEARNERS) and merged["metric"] == "return"
    assert (tmp_path / "benchmarks" / "Pendulum-v1" / "compare.png").stat().st_size > 10_000


def test_every_benchmarks_part_asks_for_the_peers_extra_before_it_trains(monkeypatch):
    """Without stable-baselines3 the part would train somarm's learners for minutes and then fail on TD3."""
    monkeypatch.setattr(runner, "peers_missing", lambda: "TD3 and SAC need the peers extra")
    for name in ("benchmarks", "benchmarks_pendulum", "benchmarks_reacher", "peers"):
        with pytest.raises(ValueError, match="need the peers extra"):
            runner.check_names([name])
    assert runner.check_names(["reach2"]) == ["reach2"]


def test_a_killed_comparison_goes_on_with_resume_keeping_its_finished_seeds(tmp_path, capsys):
    import subprocess

    from processes import still_running

    out = tmp_path / "cmp"
    argv = ["compare", "throw_distance", "--learners", "somq,tabular", "--samples", "2000", "--seeds", "3",
            "--observations", "30", "--out", str(out), "--resume"]
    proc = subprocess.Popen([sys.executable, "-m", "somarm.cli", *argv, "--no-progress"], stderr=subprocess.PIPE)
    first = out / "seeds" / "somq-0.json"
    while proc.poll() is None and not first.exists():
        still_running([proc.pid], 0.05)
    proc.kill()
    proc.wait(timeout=30)
    assert first.exists(), proc.stderr.read().decode()
    kept = json.loads(first.read_text())
    assert main(argv) == 0
    err = capsys.readouterr().err
    assert "throw_distance/somq seed 0: 2000 samples" in err and "(kept from the earlier run)" in err
    result = json.loads((out / "compare.json").read_text())
    assert result["complete"] and np.array(result["learners"]["somq"]["error"]).shape == (5, 3)
    assert [row[0] for row in result["learners"]["somq"]["error"]] == kept["values"]
    # Run alone, seed 0 gives the same errors: what was kept is what training gives.
    alone = compare.compare(compare.CompareConfig(task="throw_distance", learners=("somq",), samples=2000,
                                                  seeds=1, observations=30), tmp_path / "alone", progress=False)
    assert [row[0] for row in alone["learners"]["somq"]["error"]] == kept["values"]
    # A damaged record, and records made with other settings, are trained again, each said in one line.
    (out / "seeds" / "tabular-2.json").write_text("{")
    assert main(argv) == 0
    err = capsys.readouterr().err
    assert f"{out / 'seeds' / 'tabular-2.json'} is damaged: " in err and "training that seed again" in err
    assert main([*argv[:9], "40", *argv[10:]]) == 0
    assert "was made with other settings; training that seed again" in capsys.readouterr().err
    assert json.loads((out / "compare.json").read_text())["observations"] == 40


def test_somq_answers_with_the_winning_unit_and_somq_plus_interpolates_on_a_benchmark_preset():
    def settings(kind, task):
        return compare.make_plan(compare.CompareConfig(task=task, learners=(kind,), seeds=1)).runners[kind].settings

    assert settings("somq", "gym:Pendulum-v1").response == "winner"
    plus = settings("somq+", "gym:Pendulum-v1")
    assert plus.response == "interpolated" and plus.input_shape == settings("somq", "gym:Pendulum-v1").input_shape
    assert settings("somq", "reach2").response == "winner"
    assert settings("tabular", "gym:Pendulum-v1").gamma == 0.98  # returns, not the next reward
    assert settings("tabular", "reach2").gamma == 0.0


def test_a_plan_resolves_the_task_parameters_and_each_learners_budget_once():
    config = compare.CompareConfig(task="reach2", learners=("somq", "td3"), samples=300, peer_samples=120,
                                   seeds=2, seed=4)
    plan = compare.make_plan(config)
    assert list(plan.runners) == ["somq", "td3"] and plan.seeds == [4, 5]
    assert plan.runners["somq"].rungs == [100, 200, 300] and plan.runners["td3"].rungs == [100, 120]
    assert plan.params == json.loads(json.dumps(plan.params))  # what compare.json and the seed records hold
    assert isinstance(plan.runners["td3"], compare.PeerRunner) and isinstance(plan.runners["somq"], compare.OurRunner)


def test_the_pendulum_speed_claim_fails_when_som_q_never_reaches_the_target_and_td3_does():
    from somarm.reproduce import benchmarks

    def measured(somq, somq_plus, td3):
        finals = {k: (-150.0 if k in ("td3", "sac") else -250.0, 1.0) for k in benchmarks.LEARNERS}
        to_target = {**{k: None for k in benchmarks.LEARNERS}, "somq": somq, "somq+": somq_plus, "td3": td3}
        return {"Pendulum-v1": {"final": finals, "random": -1200.0, "converged": -150.0, "to_target": to_target}}

    def speed(m):
        return benchmarks._claims(m, 5)[-1].holds

    assert speed(measured(None, None, (20_000, 260.0))) is False
    assert speed(measured(None, None, None)) is None
    assert speed(measured((100_000, 60.0), (80_000, 40.0), (20_000, 260.0))) is True  # the faster of the two
    named = benchmarks._claims(measured((100_000, 60.0), (80_000, 40.0), (20_000, 260.0)), 5)[-1].measured
    assert named.startswith("SOM-Q+ (interpolated): 80000 samples, 40")
    assert speed(measured((100_000, 60.0), None, (20_000, 260.0))) is False
    claim = benchmarks._claims(measured(None, None, None), 5)[0]
    assert "-250.0 ± 1.0" in claim.measured and claim.holds is False


def test_the_yardsticks_balance_and_reach_and_rounding_them_to_the_presets_grids_costs_what_the_report_says():
    from somarm.reproduce import yardsticks

    pendulum = dict(yardsticks.inverted_pendulum(2, 0))
    assert pendulum["linear controller"] == 1000.0  # every step of both episodes balanced
    assert pendulum["torque rounded to 3 torques over the whole box (-3, 0, 3)"] < 200.0
    assert pendulum["torque rounded to the preset's 11 torques (-0.5, -0.4, -0.3, -0.2, -0.1, 0, 0.1, 0.2, 0.3, 0.4, "
                    "0.5)"] > 900.0
    assert pendulum["torque rounded to 9 torques packed near 0 (3 s^3, s even in [-1, 1])"] > 900.0
    reacher = dict(yardsticks.reacher(20, 0))
    assert reacher["PD law"] > -6.0 and reacher["no torque"] < -9.0
    assert reacher["PD law rounded to a 3x3 grid over the whole box (-1, 0, 1 per joint)"] < reacher["PD law"] - 2.0
    assert reacher["PD law rounded to the preset's 3x3 grid (-0.1, 0, 0.1 per joint)"] > reacher["PD law"] - 1.0
    assert pendulum["torque rounded to 3 torques over a sixth of the box (-0.5, 0, 0.5)"] > 500.0
    lines = yardsticks.table({"Reacher-v5": [("PD law", -5.0)]}, 5)
    assert "| Reacher-v5 | PD law | -5.0 |" in lines and yardsticks.table({}, 5) == []
    # Rounding and cell centres are what they say.
    assert yardsticks.round_to(lambda o: np.array([0.4, -2.0]), np.array([-1.0, 0.0, 1.0]))(None).tolist() == [0.0, -1.0]
    centred = yardsticks.cell_centre(lambda o: o, np.zeros(2), np.ones(2), 3)
    assert centred(np.array([0.3, 0.9])).tolist() == [0.5, 1.0]


def test_a_policy_seen_through_an_input_map_answers_for_its_nearest_units():
    from somarm.reproduce import yardsticks

    class Doubling:  # a task whose scaled observation is half the environment's
        scale = staticmethod(lambda obs: np.asarray(obs) / 2.0)
        unscale = staticmethod(lambda u: np.asarray(u) * 2.0)

    units = np.array([[0.0], [1.0], [3.0]])
    nearest = yardsticks.through_map(lambda o: o, Doubling(), units)
    assert nearest(np.array([1.4])).tolist() == [2.0]  # scaled 0.7, nearest unit 1.0, unscaled 2.0
    blended = yardsticks.through_map(lambda o: o, Doubling(), units, 2)
    # scaled 0.5: units 0 and 1 at 0.5 each, the next (3.0) at 2.5: weights 2 - 0.4 each, a blend of 0 and 2
    assert blended(np.array([1.0])).tolist() == [1.0]
    assert blended(np.array([2.0])).tolist() == [2.0]  # on a unit: that unit alone
    # weights fall to 0 as a unit leaves the nearest set: at scaled 2.0 (units 1 and 3 at 1.0, unit 0 at 2.0)
    assert blended(np.array([4.0])).tolist() == [4.0]


def test_the_yardsticks_see_the_state_through_the_presets_learned_input_map():
    from somarm.reproduce import yardsticks

    rows = dict(yardsticks.inverted_pendulum(2, 0, map_steps=300))
    seen = [label for label in rows if label.startswith("state seen through the preset's 20x20 input map after 300")]
    # the nearest unit, the blend, and the blend of each unit's torque rounded to 3 grids
    assert len(seen) == 5 and all(1.0 <= rows[label] <= 1000.0 for label in seen)
    assert any(label.endswith("each unit's torque rounded to 21 even in [-1, 1]") for label in seen)
    assert not any(label.startswith("state seen") for label in dict(yardsticks.inverted_pendulum(1, 0)))
    own = [label for label in rows if "map learned on the controller's own states (300 steps" in label]
    assert len(own) == 2 * len(yardsticks.CONTROLLER_MAP_SHAPES) and all(1.0 <= rows[label] <= 1000.0 for label in own)
    reacher = dict(yardsticks.reacher(2, 0, map_steps=300))
    own = [label for label in reacher if "map learned on the controller's own states (300 steps, torque noise sd 0.1)"
           in label]
    # 50 steps, each at most 0.41 from the target with a torque cost of at most 2 (clipped to [-1, 1])
    assert len(own) == 2 * len(yardsticks.CONTROLLER_MAP_SHAPES) and all(-121.0 <= reacher[label] < 0.0 for label in own)
    assert not any("own states" in label for label in dict(yardsticks.reacher(1, 0)))


def test_a_map_learned_on_the_controllers_states_gathers_round_them_and_is_reproducible():
    from somarm.learners import presets
    from somarm.reproduce import yardsticks
    from somarm.tasks import gym_envs

    env_id = "InvertedPendulum-v5"
    low, high = (np.array(b) for b in gym_envs.estimate_bounds(
        gym_envs.GymParams(env_id), 0, how=presets.task_params_of("invertedpendulum", "gym:" + env_id)))
    scaling = gym_envs.BoxScaling(low, high)
    assert np.allclose(scaling.unscale(scaling.scale(np.array([0.3, -0.1, 1.0, -2.0]))), [0.3, -0.1, 1.0, -2.0])

    def linear(obs):
        return np.array([yardsticks.INVERTED_PENDULUM_GAINS @ obs])

    units = yardsticks.controller_map(env_id, linear, scaling, (5, 5), 2000, 0.5, 0)
    # 25 units that start uniform over [0, 1]^4 end where a balanced pole's states are: none at an edge
    assert units.shape == (25, 4) and units.min() > 0.3 and units.max() < 0.9
    assert np.array_equal(units, yardsticks.controller_map(env_id, linear, scaling, (5, 5), 2000, 0.5, 0))


def test_a_peers_seed_record_does_not_depend_on_the_observation_scaling_it_never_reads():
    from types import SimpleNamespace

    config = compare.CompareConfig(task="gym:InvertedPendulum-v5", learners=("somq", "td3"), samples=100,
                                   seeds=1, seed=0, episodes=5, eval_seed=0)
    score = SimpleNamespace(episodic=True)
    scalings = [{"observation_low": [-1.0, -0.2, -2.0, -4.0], "observation_high": [1.0, 0.2, 2.0, 4.0]},
                {"observation_low": [-1.0, -0.2, -1.9, -4.2], "observation_high": [1.0, 0.2, 1.9, 4.2]}]
    runners = {"td3": compare.PeerRunner("td3", 100, "InvertedPendulum-v5"),
               "sac": compare.PeerRunner("sac", 100, "InvertedPendulum-v5"),
               "somq": compare.OurRunner("somq", None, 100)}

    def fingerprint(kind, params):
        return compare.Plan(config, params, runners).fingerprint(kind, 3, score, {"a": 1})

    # TD3 and SAC train and act on the environment's own observations: the scaling estimated at
    # another seed leaves their record valid; somarm's learners see the scaled state, so theirs is not
    assert fingerprint("td3", scalings[0]) == fingerprint("td3", scalings[1])
    assert fingerprint("td3", scalings[0])["task_params"] == {}
    assert fingerprint("somq", scalings[0]) != fingerprint("somq", scalings[1])
    # a keyword the environment is made with still counts for everyone
    assert fingerprint("sac", {**scalings[0], "reset_noise_scale": 0.1}) != fingerprint("sac", scalings[0])


def test_the_benchmarks_report_quotes_the_zoo_as_published_or_says_it_has_nothing():
    from somarm.reproduce import benchmarks

    lines = benchmarks._published(("Pendulum-v1",))
    assert "- TD3 on Pendulum-v1: -152 ± 90 after 20000 steps" in lines
    lines = benchmarks._published(("MountainCarContinuous-v0",))
    assert "- SAC on MountainCarContinuous-v0: 94.7 after 50000 steps" in lines  # not padded to 94.700
    lines = benchmarks._published(("InvertedPendulum-v5",))
    assert lines[0] == "RL Baselines3 Zoo publishes no TD3 or SAC result for InvertedPendulum-v5."
    assert lines[-1] == "Gymnasium's reward thresholds: InvertedPendulum-v5 950."


def test_a_suite_task_is_compared_as_a_gymnasium_environment_with_the_peers_on_the_suites_own_physics():
    config = compare.CompareConfig(task="dmc:cartpole-balance", learners=("somq", "sac"), samples=200,
                                   peer_samples=200, seeds=1, episodes=1)
    plan = compare.make_plan(config)
    sac = plan.runners["sac"]
    assert sac.gym_id == "somarm-dmc/cartpole-balance-v0" and sac.budget == 200
    env, described = sac._env(config.task, plan.params)
    assert env.unwrapped.domain == "cartpole" and described.startswith("somarm-dmc/cartpole-balance-v0")
    env.close()
    assert compare.default_samples("dmc:cartpole-balance") == tasks.record("dmc:cartpole-balance").n_steps


def test_a_record_lacking_a_setting_at_its_default_is_kept_and_one_lacking_another_is_trained_again(tmp_path, capsys):
    out = tmp_path / "cmp"
    argv = ["compare", "reach2", "--learners", "somq", "--samples", "400", "--seeds", "1",
            "--observations", "20", "--out", str(out), "--resume"]
    assert main(argv) == 0
    path = out / "seeds" / "somq-0.json"
    record = json.loads(path.read_text())
    settings = record["fingerprint"]["settings"]
    from somarm.learners.somq import SOMQConfig

    defaults = SOMQConfig().to_dict()
    at_default = next(k for k, v in settings.items() if defaults[k] == v)
    elsewhere = next(k for k, v in settings.items() if defaults[k] != v)
    # A setting added since, at its default, changes nothing the record holds: kept.
    del settings[at_default]
    path.write_text(json.dumps(record))
    capsys.readouterr()
    assert main(argv) == 0
    assert "(kept from the earlier run)" in capsys.readouterr().err
    # A record lacking a setting that is not at its default was made otherwise: trained again.
    record = json.loads(path.read_text())
    del record["fingerprint"]["settings"][elsewhere]
    path.write_text(json.dumps(record))
    assert main(argv) == 0
    assert "was made with other settings; training that seed again" in capsys.readouterr().err


def test_a_presets_action_repeat_and_angles_are_its_learners_alone_and_its_samples_are_the_suites_steps(monkeypatch):
    config = compare.CompareConfig(task="dmc:pendulum-swingup", learners=("somq", "sac"), samples=1000,
                                   peer_samples=200, seeds=1, seed=3, episodes=1)
    plan = compare.make_plan(config)
    ours, theirs = plan.params_for("somq"), plan.params_for("sac")
    assert ours["action_repeat"] == 5 and ours["angles"] == [[0, 1]] and len(ours["observation_low"]) == 2
    assert "action_repeat" not in theirs and "angles" not in theirs and len(theirs["observation_low"]) == 3
    assert plan.scorer("sac").task.scale_low.size == 3 and plan.scorer("somq").task.scale_low.size == 2
    env, _ = plan.runners["sac"]._env(config.task, theirs)
    assert env.unwrapped.action_repeat == 1 and env.observation_space.shape == (3,)
    env.close()
    # the peers' records keep their fingerprint: only what the run itself sets reaches them
    assert plan.fingerprint("sac", 0, plan.scorer(), {})["task_params"] == {}
    trained = []
    monkeypatch.setattr(compare, "_train_ours", lambda task, learner, steps: trained.append(steps))
    plan.runners["somq"].run(plan, 3, plan.scorer("somq"))
    assert plan.runners["somq"].rungs == [100, 200, 500, 1000] and trained == [20, 20, 60, 100]  # 5 steps a decision


def test_every_learner_counts_the_suites_steps_whoever_holds_its_actions():
    # the run's own action_repeat reaches TD3 and SAC too, and their samples are the suite's steps as well
    config = compare.CompareConfig(task="dmc:cartpole-balance", learners=("somq", "sac"), samples=1000,
                                   peer_samples=1000, seeds=1, episodes=1, task_params={"action_repeat": 4})
    plan = compare.make_plan(config)
    assert plan.params_for("sac")["action_repeat"] == 4 == plan.params_for("somq")["action_repeat"]
    assert [compare.decisions(n, plan.params_for("sac")) for n in (100, 1000)] == [25, 250]
    assert compare.decisions(1000, {}) == 1000
