"""The dmc tuning scripts: action repeat sums the suite's own rewards, and the yardstick the report
leans on (the LQR law through the dmc preset's forces balances the cartpole) holds."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("dm_control")
pytest.importorskip("gymnasium")

SCRIPTS = Path(__file__).resolve().parents[2] / "scripts"


def _script(name: str):
    spec = importlib.util.spec_from_file_location(name, SCRIPTS / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_action_repeat_holds_each_action_k_suite_steps_and_sums_their_rewards():
    import gymnasium

    from somarm.tasks.dmc import SuiteEnv

    name = _script("tune_dmc")._register_repeat("dmc:cartpole-balance", 4)
    held = gymnasium.make(name[len("gym:"):])
    plain = SuiteEnv("cartpole", "balance")
    held.reset(seed=3)
    plain.reset(seed=3)
    rng = np.random.default_rng(0)
    steps = 0
    done = False
    while not done:
        action = rng.uniform(-1.0, 1.0, 1)
        observation, reward, terminated, truncated, _ = held.step(action)
        expected = sum(plain.step(action)[1] for _ in range(4))
        assert reward == pytest.approx(expected, rel=1e-12, abs=1e-12)
        steps += 1
        done = terminated or truncated
    assert steps == 1000 // 4


def test_a_tuning_row_records_each_episodes_return_and_the_training_steps_paid_by_each_rung(tmp_path):
    import json
    import subprocess
    import sys

    record = tmp_path / "rows.jsonl"
    subprocess.run([sys.executable, str(SCRIPTS / "tune_dmc.py"), "dmc:point_mass-easy", "--seeds", "100",
                    "--samples", "1500", "--rungs", "500", "--episodes", "3", "--record", str(record)],
                   check=True, capture_output=True, timeout=300)
    row, = [json.loads(line) for line in record.read_text().splitlines()]
    assert len(row["returns"]) == 3 and row["greedy"] == pytest.approx(np.mean(row["returns"]), abs=0.06)
    paid = row["paid_training_steps"]
    assert list(paid) == ["500", "1500"] and 0 <= paid["500"] <= paid["1500"] <= 1500


def test_the_lqr_law_through_the_dmc_presets_forces_balances_the_cartpole():
    yardsticks = _script("dmc_yardsticks")
    from somarm.tasks.dmc import SuiteEnv

    env = SuiteEnv("cartpole", "balance")
    gain = yardsticks._cartpole_gain(env)
    forces = np.linspace(-1 / 6, 1 / 6, 11)

    def policy(o):
        x, cos, sin, xdot, thetadot = o
        return yardsticks._rounded(np.clip(-gain @ np.array([x, np.arctan2(sin, cos), xdot, thetadot]), -1, 1), forces)

    assert yardsticks._returns(env, policy, 1)[0] >= 990.0
    assert yardsticks._returns(env, lambda o: 0.0, 1)[0] < 990.0  # pushing nothing does not: the bound can fail


def test_the_swing_up_law_lifts_the_pendulum_with_the_whole_box_and_not_with_the_dmc_presets_torques():
    yardsticks = _script("dmc_yardsticks")
    laws = dict(yardsticks.controllers()["dmc:pendulum-swingup"])
    from somarm.tasks.dmc import SuiteEnv

    env = SuiteEnv("pendulum", "swingup")
    assert yardsticks._returns(env, laws["energy pumping and PD catch rounded to 11 torques over the box"], 1)[0] >= 600.0
    assert yardsticks._returns(env, laws["energy pumping and PD catch rounded to the dmc preset's 11 torques"], 1)[0] == 0.0


def test_a_preset_with_n_step_targets_learns_a_controller_by_imitation_and_follows_it():
    yardsticks = _script("dmc_yardsticks")
    from somarm import tasks
    from somarm.reproduce import yardsticks as held
    from somarm.tasks.dmc import gym_id

    task = "dmc:cartpole-balance"
    law = yardsticks.controllers()[task][0][1]
    scaling = tasks.make(task, seed=100, observation_low=yardsticks.BOUNDS[task][0],
                         observation_high=yardsticks.BOUNDS[task][1])
    states, actions = held.controller_states(gym_id(task), law, scaling, 20_000, 0.1, 100)
    policy = held.through_representation(gym_id(task), states, actions, scaling, {}, 100, preset="dmc_balance")
    learned = np.array([policy(o)[0] for o in scaling.unscale(states[-500:])])
    # dmc_balance's 30-step targets are set aside (gamma 0); a learner that held nothing would not follow the law
    assert np.corrcoef(learned, actions[-500:, 0])[0, 1] > 0.6


def test_the_cart_replay_finds_the_rail_before_the_fall_under_a_constant_push_and_neither_at_rest():
    replay = _script("dmc_cart_replay").replay
    from somarm.tasks.dmc import SuiteEnv

    env = SuiteEnv("cartpole", "balance")
    pushed, = replay(env, lambda o: 1.0, 1)
    assert pushed["rail_m"] == pytest.approx(1.8)
    assert pushed["mean_abs_force"] == pytest.approx(1.0)
    assert pushed["cart_max_m"] >= pushed["rail_m"] - 0.05 and pushed["cart_at_rail_step"] is not None
    assert pushed["pole_fell_step"] is not None and pushed["cart_at_rail_step"] < 1000
    lqr_gain = _script("dmc_yardsticks")._cartpole_gain(env)

    def lqr(o):
        x, cos, sin, xdot, thetadot = o
        return np.clip(-lqr_gain @ np.array([x, np.arctan2(sin, cos), xdot, thetadot]), -1, 1)

    held, = replay(env, lqr, 1)
    assert held["cart_at_rail_step"] is None and held["pole_fell_step"] is None and held["return"] > 990.0
    assert held["steps_upright"] == 1000 and held["pole_top_cos"] > 0.99


def test_the_cart_replay_sees_the_swing_up_pole_rise_under_pumping_and_stay_down_at_rest():
    replay = _script("dmc_cart_replay").replay
    pump = _script("dmc_yardsticks").pump
    from somarm.tasks.dmc import SuiteEnv

    env = SuiteEnv("cartpole", "swingup")
    still, = replay(env, lambda o: 0.0, 1)
    assert still["pole_top_cos"] < -0.9 and still["steps_upright"] == 0
    pumped, = replay(env, pump(1 / 6), 1)
    assert pumped["pole_top_cos"] > 0.99 and pumped["steps_upright"] > 0


def test_the_swing_up_law_on_a_uniform_30x30_grid_still_lifts_the_pendulum_and_a_coarse_grid_does_not():
    yardsticks = _script("dmc_yardsticks")
    laws = dict(yardsticks.controllers()["dmc:pendulum-swingup"])
    from somarm.tasks.dmc import SuiteEnv

    env = SuiteEnv("pendulum", "swingup")
    on = "energy pumping and PD catch rounded to 11 torques over the box, on a {0}x{0} grid over angle and velocity"
    assert yardsticks._returns(env, laws[on.format(30)], 1)[0] >= 600.0
    assert yardsticks._returns(env, laws[on.format(10)], 1)[0] < 600.0  # the bound can fail


def test_the_pendulum_hold_keeps_the_pole_up_from_near_upright_and_never_lifts_it_from_below():
    from somarm.reproduce.yardsticks import pendulum_hold
    from somarm.tasks.dmc import SuiteEnv, flatten

    env = SuiteEnv("pendulum", "swingup")
    totals = {}
    for start in (0.1, np.pi - 0.1):  # the hinge angle from upright (the suite's 0)
        env.reset(seed=0)
        with env.physics.reset_context():
            env.physics.named.data.qpos["hinge"] = start
            env.physics.named.data.qvel["hinge"] = 0.0
        observation = flatten(env.environment.task.get_observation(env.physics))
        total = 0.0
        for _ in range(1000):
            observation, reward, _, _, _ = env.step(pendulum_hold(observation[None])[0])
            total += reward
        totals[start] = total
    env.close()
    assert totals[0.1] >= 990.0
    assert totals[np.pi - 0.1] == 0.0
    assert pendulum_hold(np.array([[np.cos(1.0), np.sin(1.0), 0.0]]))[0, 0] == 0.0  # 57 degrees out: no torque


def _watched(task: str, what: str, probe):
    """The yardstick ``what`` of suite ``task`` on reset seed 0, with ``probe(env)`` after each of its steps;
    and pushing nothing on the same episode: (its return, the probes, the return at rest, the law)."""
    yardsticks = _script("dmc_yardsticks")
    laws = dict(yardsticks.controllers()[task])
    from somarm.tasks.dmc import SuiteEnv, split_name

    env, seen = SuiteEnv(*split_name(task)), []
    total = yardsticks._returns(env, laws[what], 1, watch=lambda episode, e, a: seen.append(probe(e)))[0]
    still = yardsticks._returns(env, laws["no force"], 1)[0]
    env.close()
    return total, seen, still, laws[what]


def test_energy_pumping_at_the_dmc_presets_largest_force_brings_the_cartpoles_pole_upright():
    pumped, tops, still, _ = _watched("dmc:cartpole-swingup",
                                      "energy pumping at the dmc preset's largest force (a sixth of the box), no catch",
                                      lambda e: float(e.physics.named.data.qpos["hinge_1"][0]))
    assert max(np.cos(tops)) > 0.99  # the pole passes upright
    assert pumped >= 150.0
    assert still < 150.0  # hanging still does not: the bound can fail


def test_the_reach_law_on_the_dmc_2d_grid_puts_the_finger_on_the_hard_target_and_pushing_nothing_does_not():
    reached, gaps, still, rounded = _watched(
        "dmc:reacher-hard", "joint-space PD on the inverse kinematics rounded to the dmc_2d preset's 3x3 grid",
        lambda e: e.physics.finger_to_target_dist())
    assert gaps[-1] < 0.025  # the finger ends on the target (its radius and the finger's)
    assert reached >= 900.0
    assert still < 100.0  # an arm left alone does not: the bound can fail
    from somarm.tasks.dmc import SuiteEnv

    env = SuiteEnv("reacher", "hard")
    assert set(np.unique(np.concatenate([rounded(env.reset(seed=k)[0]) for k in range(5)]))) <= {-1.0, 0.0, 1.0}
    env.close()


def test_the_hold_on_tuning_seeds_scores_where_an_evaluation_episode_starts_near_upright_and_nowhere_else():
    rows = _script("dmc_yardsticks").hold_on_seeds([100, 101], 10)
    assert [row["seed"] for row in rows] == [100, 101] and all(len(row["returns"]) == 10 for row in rows)
    assert max(rows[0]["returns"]) > 900.0  # seed 100: an episode starts where the pole can be caught
    assert max(rows[1]["returns"]) < 10.0  # seed 101: none does, so only a swing-up could score there


def test_the_catch_replay_counts_the_paid_steps_from_rest_the_hold_keeps_and_no_torque_loses():
    from somarm.reproduce.yardsticks import pendulum_hold
    from somarm.tasks.dmc import SuiteEnv

    catch = _script("dmc_pendulum_catch")
    env = SuiteEnv("pendulum", "swingup")
    held = lambda o: pendulum_hold(o[None])[0]  # noqa: E731
    (_, near), (_, far) = catch.catches(env, held, [5.0, 45.0], 200)
    assert min(near) >= 190 and max(far) == 0  # held from 5 degrees either side; from 45 the torque cannot
    assert max(catch.paid_from_rest(env, lambda o: np.zeros(1), sign * np.radians(5.0), 200) for sign in (-1, 1)) < 50
    env.close()


def test_units_near_upright_count_by_angle_and_speed():
    catch = _script("dmc_pendulum_catch")
    deg = np.radians([0.0, 9.0, -15.0, 0.0, 180.0])
    units = np.stack([np.cos(deg), np.sin(deg), [0.0, 1.0, 0.0, 4.0, 0.0]], axis=1)
    assert [catch.units_near_upright(units, d) for d in (10, 20)] == [2, 3]


@pytest.mark.parametrize("args, message", [
    (["--seed", "5"], "seed 5: tuning seeds are 100-199"),
    (["--set", "replay=x"], "replay=x: replay must be a whole number"),
    (["--set", "replay"], "--set replay: give KEY=VALUE"),
    (["--preset", "nope"], "unknown preset 'nope'; allowed: "),
])
def test_a_tuning_scripts_bad_argument_ends_in_one_line(args, message):
    import subprocess
    import sys

    done = subprocess.run([sys.executable, str(SCRIPTS / "dmc_pendulum_catch.py"), *args], capture_output=True,
                          text=True, timeout=120)
    assert done.returncode == 1 and done.stderr.startswith(message) and done.stderr.count("\n") == 1, done.stderr
