import dataclasses

import numpy as np
import pytest

from somarm import tasks
from somarm.learners import choices, presets
from somarm.learners.motoric import MotoricConfig
from somarm.learners.schedules import ExponentialDecay, InverseDecay, Schedule
from somarm.learners.somq import SOMQConfig

NAMES = ["table1", "table2", "table4", "table5", "table7", "table7a", "table1+", "table2+", "table5+"]
BENCHMARKS = ["gym", "pendulum", "mountaincar", "invertedpendulum", "reacher"]
SUITE = ["dmc", "dmc_balance", "dmc_2d", "dmc_point_mass", "dmc_pendulum", "dmc_cartpole"]


def test_every_table_is_available_by_name_with_a_description():
    assert list(presets.PRESETS) == [*NAMES, "obstacle", *BENCHMARKS, *SUITE]
    for name in NAMES:
        assert isinstance(presets.get(name), SOMQConfig)
        line = presets.describe(name)
        assert line.startswith("Table") and "\n" not in line and "Fig" in line
        assert presets.PRESETS[name].config is presets.get(name)


def test_plus_presets_change_only_schedules_of_their_table_and_table1_plus_the_circles():
    for name, changed in (("table1+", {"lambda_a", "periodic_actions"}), ("table5+", set(SOMQConfig.SCHEDULES))):
        base, plus = presets.get(name[:-1]).to_dict(), presets.get(name).to_dict()
        assert {key for key in base if base[key] != plus[key]} == changed
        assert plus["response"] == "winner"
    assert presets.get("table1+").lambda_a.value(10**6) == 0.1 and presets.get("table1+").periodic_actions
    assert presets.get("table5+").epsilon.value(10**6) == 0.02


def test_table2_plus_is_table2_on_circles_with_the_interpolated_response_and_a_slower_epsilon():
    base, plus = presets.get("table2").to_dict(), presets.get("table2+").to_dict()
    assert {key for key in base if base[key] != plus[key]} == {"periodic_actions", "response", "epsilon"}
    assert plus["periodic_actions"] is True and plus["response"] == "interpolated"
    epsilon, table2 = presets.get("table2+").epsilon, presets.get("table2").epsilon
    # Larger than Table 2's when the goals move (step 20,000), so an action unit can travel to a quadrant
    # left without one; the same floor at the end of the run.
    assert epsilon.value(20_000) == pytest.approx(0.016) and table2.value(20_000) == 0.01
    assert epsilon.value(40_000) == epsilon.floor == table2.floor == 0.01
    assert presets.PRESETS["table2+"].task == "four_goals"


def test_obstacle_preset_discounts_the_future_and_is_described_as_beyond_the_paper():
    preset = presets.PRESETS["obstacle"]
    assert preset.task == "reach2_obstacle" and preset.config.gamma == 0.9
    assert preset.config.input_shape == (20, 20) and preset.config.action_shape == (5, 5)
    assert preset.config.input_init is None and preset.n_steps == 500_000  # the observation bounds; long runs
    assert presets.describe("obstacle").startswith("beyond the paper")


def test_benchmark_presets_explore_by_optimism_over_a_frozen_torque_grid():
    for name in BENCHMARKS[1:]:
        preset = presets.PRESETS[name]
        c = preset.config
        assert preset.task.startswith("gym:") and presets.describe(name).startswith("beyond the paper")
        # no random units and no perturbations: optimistic initial values alone explore
        assert c.p.value(0) == 0 and c.epsilon.value(0) == 0
        assert c.action_init == "grid" and c.lambda_a.value(0) == 0
        # a frozen grid; its Q neighbourhood spreads only over InvertedPendulum's 11 close torques and
        # Reacher-v5's 3x3 grid (whose parabola needs a torque's neighbours' values)
        assert (c.n_a.value(0) > 0) == (name in ("invertedpendulum", "reacher"))
        # the paper's one input map, except on Reacher-v5's 10 observed dimensions (a map per pair) and
        # InvertedPendulum-v5 (one map over three of its four dimensions)
        assert c.grouped == (name in ("reacher", "invertedpendulum"))
        assert c.response == "interpolated"
    # optimism: above every discounted return (Pendulum's rewards are <= 0; an InvertedPendulum step
    # earns 1, so at most 1 / (1 - 0.99) = 100); MountainCar's q_init only above the goal's value from
    # the valley (100 x 0.99^100 = 37 > 30 > the action costs): untried pairs at 100 outbid the goal
    assert presets.get("pendulum").q_init == 0.0 and presets.get("pendulum").action_shape == (3,)
    assert presets.get("invertedpendulum").q_init >= 100 and 0 < presets.get("mountaincar").q_init < 37
    # InvertedPendulum: 11 torques 0.1 apart over a sixth of the box, fine enough to balance
    pendulum = presets.get("invertedpendulum")
    assert pendulum.action_shape == (11,) and abs(6 * pendulum.grid_span - 1) < 1e-12
    # MountainCar: small pushes on the grid, and no torque of 0 (a resting car's cell would keep it)
    from somarm.learners.somq import grid_actions

    torques = grid_actions(presets.get("mountaincar").action_shape, np.array([-1.0]), np.array([1.0])).ravel()
    assert np.all(torques != 0) and np.min(np.abs(torques)) <= 0.5
    # MountainCar's input map stays at its uniform start: one settling on the valley leaves the hills coarse
    assert presets.get("mountaincar").lambda_s.value(0) == 0 and presets.get("mountaincar").n_s.value(0) == 0
    # Reacher: a 3x3 grid over a tenth of the torque box, fine pushes to hold the fingertip on the target
    assert presets.get("reacher").action_shape == (3, 3) and presets.get("reacher").grid_span == 0.1
    # the generic preset cannot know a reward range, so it explores with random units and perturbations
    generic = presets.get("gym")
    assert generic.q_init == 0.0 and generic.p.value(10**6) > 0 and generic.epsilon.value(10**6) > 0


def test_table1_values():
    c, f = presets.get("table1"), InverseDecay(1000)
    assert c.input_shape == (50,) and c.action_shape == (50,) and c.input_init == (0.0, 1.0)
    assert (c.n_s, c.n_a, c.epsilon) == (Schedule(20, f), Schedule(20, f), Schedule(0.1, f))
    assert c.alpha == c.lambda_s == c.lambda_a == c.p == Schedule(1, f)
    assert c.gamma == 0 and c.neighbourhood_q


def test_table2_values_and_floors():
    c, f = presets.get("table2"), InverseDecay(500)
    assert c.input_shape == (10, 10) and c.action_shape == (8,)
    assert c.alpha == Schedule(1, f, 0.1) and c.lambda_a == Schedule(1, f, 0.1)
    assert c.epsilon == Schedule(0.1, f, 0.01) and c.p == Schedule(0.25, f)
    assert c.n_s == Schedule(10, f) and c.n_a == Schedule(3, f)
    assert c.epsilon.value(10**6) == 0.01  # the floor keeps residual exploration after the change


def test_table4_and_table5_relation():
    t4, t5 = presets.get("table4"), presets.get("table5")
    assert t4.input_shape == (1,) and t4.action_shape == (30,)
    assert t4.n_a == Schedule(15, ExponentialDecay(0.999), 2) and t4.p.floor == 0.5 and t4.alpha.floor == 0.05
    assert presets.PRESETS["table4"].n_steps == 4000
    f = ExponentialDecay(0.9985)
    assert t5.input_shape == (30,) and t5.action_shape == t4.action_shape
    assert (t5.n_s, t5.n_a, t5.lambda_s) == (Schedule(15, f), Schedule(25, f), Schedule(0.3, f))
    # "Minimum values are no longer used": no floor anywhere, everything on f = 0.9985^throw.
    assert all(getattr(t5, n).floor == 0 and getattr(t5, n).decay == f for n in SOMQConfig.SCHEDULES)


def test_table7_and_experiment_a():
    t7, t7a = presets.get("table7"), presets.get("table7a")
    assert t7.input_shape == (10, 10) and t7.action_shape == (30,)
    assert t7.n_s == t7.n_a == Schedule(7, ExponentialDecay(0.9997))
    assert t7a.input_shape == (30,) and t7a.n_s == Schedule(7, ExponentialDecay(0.9985))
    # Experiment A differs only in its input map and in f.
    faster = {n: getattr(t7, n).with_changes(decay=ExponentialDecay(0.9985)) for n in SOMQConfig.SCHEDULES}
    assert dataclasses.replace(t7, input_shape=(30,), **faster) == t7a
    assert presets.PRESETS["table7"].n_trials == 100


def test_motoric_preset_matches_table2():
    m, t2 = presets.get_motoric("table2"), presets.get("table2")
    assert isinstance(m, MotoricConfig)
    assert m.input_shape == t2.input_shape and m.alpha == t2.alpha and m.epsilon == t2.epsilon
    assert m.lambda_a == t2.lambda_a and m.n_a == t2.n_a and m.input_init == (0.0, 1.0)
    assert dataclasses.replace(MotoricConfig(), input_init=(0.0, 1.0), epsilon_relative=True) == m
    assert presets.config_for("motoric", "table2") == m and presets.config_for("somq", "table2") == t2


def test_unknown_names_list_the_allowed():
    with pytest.raises(ValueError, match="unknown preset 'table3'; allowed: table1, table2, table4"):
        presets.get("table3")
    with pytest.raises(ValueError, match="allowed: table1"):
        presets.get_motoric("fig13")
    with pytest.raises(ValueError, match="allowed: somq, motoric"):
        presets.config_for("dqn", "table1")


def test_presets_build_learners():
    from somarm import learners

    for name in NAMES:
        for kind in ("somq", "motoric"):
            learner = learners.make(kind, presets.config_for(kind, name), observation_low=[0, 0],
                                   observation_high=[1, 1], action_low=[0, 0], action_high=[1, 1], n_trials=2)
            actions = learner.act(np.full((2, 2), 0.5))
            learner.learn(-actions.sum(axis=1))
            assert learner.t == 1


def test_the_suite_presets_are_the_invertedpendulum_recipe_with_one_map_over_every_dimension():
    base = presets.get("invertedpendulum")
    for name, actions in (("dmc", base.action_shape), ("dmc_2d", (3, 3))):
        preset = presets.PRESETS[name]
        assert preset.task.startswith("dmc:") and presets.describe(name).startswith("beyond the paper")
        config = preset.config
        assert config.input_groups == "all" and not config.grouped and config.action_shape == actions
        assert (config.gamma, config.q_init, config.alpha) == (base.gamma, base.q_init, base.alpha)
    assert presets.get("dmc_2d").grid_span == 1.0


def test_the_balance_preset_maps_the_pole_alone_with_slopes_and_30_step_targets_over_the_balancing_region():
    base, balance = presets.get("dmc").to_dict(), presets.get("dmc_balance").to_dict()
    assert {key for key in base if base[key] != balance[key]} == {"input_groups", "input_shape", "local_linear",
                                                                  "shared_slopes", "n_step", "alpha"}
    assert (balance["input_groups"], balance["input_shape"], balance["n_step"]) == ("2,4", [30, 30], 30)
    alpha = presets.get("dmc_balance").alpha  # the dmc preset's step size without its floor: it falls to 0
    assert alpha.floor == 0.0 and alpha.value(1_000_000) < 0.02 < presets.get("dmc").alpha.value(1_000_000)
    assert tasks.record("dmc:cartpole-balance").n_steps == 1_000_000
    ranges = presets.task_params_of("dmc_balance", "dmc:cartpole-balance")["observation_ranges"]
    assert ranges["2"] == [-0.25, 0.25] and sorted(ranges) == ["0", "1", "2", "3", "4"]
    assert presets.task_params_of("dmc_balance", "dmc:cartpole-swingup") == {}


def test_the_point_mass_preset_maps_each_axis_with_n_step_advantage_targets_over_the_targets_neighbourhood():
    base, point = presets.get("dmc_2d").to_dict(), presets.get("dmc_point_mass").to_dict()
    assert {key for key in base if base[key] != point[key]} == {"input_groups", "n_step", "action_gap"}
    assert (point["input_groups"], point["n_step"], point["action_gap"]) == ("0,2;1,3", 30, 0.5)
    ranges = presets.task_params_of("dmc_point_mass", "dmc:point_mass-easy")["observation_ranges"]
    assert ranges["0"] == [-0.03, 0.03] and sorted(ranges) == ["0", "1", "2", "3"]
    assert tasks.record("dmc:point_mass-easy").n_steps == 600_000


def test_the_pendulum_preset_plans_over_a_fixed_grid_of_angle_and_velocity_deciding_every_tenth_of_a_second():
    base, swing = presets.get("dmc").to_dict(), presets.get("dmc_pendulum").to_dict()
    assert {key for key in base if base[key] != swing[key]} == {
        "input_shape", "grid_span", "input_placement", "lambda_s", "gamma", "q_init", "plan", "plan_every"}
    assert (swing["input_shape"], swing["input_placement"], swing["lambda_s"]["scale"]) == ([30, 30], "grid", 0.0)
    assert (swing["grid_span"], swing["plan"], swing["plan_every"], swing["n_step"]) == (1.0, 100, 200, 1)
    asked = presets.task_params_of("dmc_pendulum", "dmc:pendulum-swingup")
    assert asked == {"angles": [[0, 1]], "action_repeat": 5, "observation_ranges": {"1": [-10.0, 10.0]}}
    # untried pairs start above any value a pair can have: at most 5 paid steps a decision, forever
    assert swing["q_init"] >= asked["action_repeat"] / (1.0 - swing["gamma"]) - 1e-9
    assert tasks.record("dmc:pendulum-swingup").preset == "dmc_pendulum"


def test_the_cartpole_swing_up_preset_starts_q_at_zero_with_n_step_targets_over_the_whole_force_box():
    base, swing = presets.get("dmc").to_dict(), presets.get("dmc_cartpole").to_dict()
    assert {key for key in base if base[key] != swing[key]} == {"q_init", "n_step", "grid_span"}
    assert (swing["q_init"], swing["n_step"], swing["grid_span"], base["q_init"]) == (0.0, 30, 1.0, 200.0)
    assert tasks.record("dmc:cartpole-swingup").preset == "dmc_cartpole"
    assert tasks.record("dmc:cartpole-swingup").n_steps == 300_000



def test_every_preset_has_its_choices_from_the_data_file_and_every_section_names_a_preset():
    sections = choices.parse(choices.CHOICES_FILE.read_text(encoding="utf-8"))
    assert list(sections) == list(presets.PRESETS)
    for name, preset in presets.PRESETS.items():
        assert preset.choices == sections[name] and preset.choices, name
        for choice in preset.choices:  # one report line each: no line breaks, no doubled spaces
            assert choice == choice.strip() and "\n" not in choice and "  " not in choice, (name, choice)


def test_choices_join_continuations_and_refuse_a_stray_line_a_doubled_section_and_unmatched_names(tmp_path):
    text = "intro, not read\n\n## a\n\n- one\n  two\n- three\n## b\n- four\n"
    assert choices.parse(text) == {"a": ("one two", "three"), "b": ("four",)}
    with pytest.raises(ValueError, match="line 3: 'stray' is neither a choice"):
        choices.parse("## a\n- one\nstray\n")
    with pytest.raises(ValueError, match="section 'a' named twice"):
        choices.parse("## a\n- one\n## a\n")
    path = tmp_path / "choices.md"
    path.write_text("## a\n- one\n## c\n- two\n")
    with pytest.raises(ValueError, match=r"presets without a section \['b'\], sections naming no preset \['c'\]"):
        choices.read(["a", "b"], path)
    assert choices.read(["a", "c"], path) == {"a": ("one",), "c": ("two",)}


def test_a_preset_asks_its_own_task_alone_for_its_scaling_as_a_copy():
    asked = presets.task_params_of("invertedpendulum", "gym:InvertedPendulum-v5")
    assert asked == presets.PRESETS["invertedpendulum"].task_params and asked
    asked["observation_widened"]["0"] = 1.0  # the caller's copy; the preset is unchanged
    assert presets.PRESETS["invertedpendulum"].task_params["observation_widened"]["0"] != 1.0
    assert presets.task_params_of("invertedpendulum", "gym:Pendulum-v1") == {}
    assert presets.task_params_of("reacher", "gym:Reacher-v5") == {"observation_ranges": {
        "6": [-5.0, 5.0], "7": [-5.0, 5.0], "8": [-0.2, 0.2], "9": [-0.2, 0.2]}}
    assert all(presets.task_params_of(name, preset.task) == {} for name, preset in presets.PRESETS.items()
               if name not in ("invertedpendulum", "reacher", "dmc_balance", "dmc_point_mass", "dmc_pendulum"))
