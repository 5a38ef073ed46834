"""The paper's parameter tables by name, so an experiment can say which table it uses.

``get("table1")`` is the ``SOMQConfig`` of Table 1; ``PRESETS["table1"]`` also holds the run facts the
paper states (task, figure, trials, averaging window). Where a table is silent the value is this
project's choice; why, each preset's ``choices`` say, read from ``preset_choices.md`` beside this module,
which holds the values only. ``table1+``, ``table2+`` and ``table5+`` change Tables 1, 2 and 5 for the
runs beyond the paper; ``obstacle``, the Gymnasium benchmarks' and the Control Suite's are this
project's throughout. Fig. 13 B's Motoric Map (``get_motoric("table2")``) takes Table 2's numbers.
"""

from __future__ import annotations

import copy
import dataclasses
from dataclasses import dataclass
from typing import Any

from somarm.learners import choices as _choices
from somarm.learners.motoric import MotoricConfig
from somarm.learners.schedules import ExponentialDecay, InverseDecay, Schedule
from somarm.learners.somq import SOMQConfig

__all__ = ["Preset", "PRESETS", "get", "get_motoric", "config_for", "describe", "motoric_from_somq",
           "task_params_of"]


@dataclass(frozen=True)
class Preset:
    """A parameter table and the run facts the paper gives with it."""

    name: str
    description: str
    """One line: which table, figure and task."""
    config: SOMQConfig
    task: str
    """The somarm task the table was used on."""
    figures: str
    n_trials: int
    """Independent trials averaged in the figure."""
    window: int | None
    """Steps each plotted point averages over (None: the figure is a map, not a curve)."""
    n_steps: int | None = None
    """Steps per trial, where the paper states it."""
    choices: tuple[str, ...] = ()
    """Values this project chose where the table is silent, and why (``preset_choices.md``)."""
    task_params: dict[str, Any] = dataclasses.field(default_factory=dict)
    """What the preset asks of its own task (``task_params_of``): how its observations are scaled."""


def _table1() -> Preset:
    f = InverseDecay(1000.0)
    config = SOMQConfig(
        input_shape=(50,), action_shape=(50,), alpha=Schedule(1.0, f), lambda_s=Schedule(1.0, f),
        lambda_a=Schedule(1.0, f), n_s=Schedule(20.0, f), n_a=Schedule(20.0, f), p=Schedule(1.0, f),
        epsilon=Schedule(0.1, f), input_init=(0.0, 1.0), epsilon_relative=True)
    return Preset("table1", "Table 1: reach2 (Figs. 7-10), 50x1 input and action maps, f = 1/(t/1000+1)",
                  config, "reach2", "7, 8, 9, 10 (and 11 with reach20)", 20, 1000)


def _table2() -> Preset:
    f = InverseDecay(500.0)
    config = SOMQConfig(
        input_shape=(10, 10), action_shape=(8,), alpha=Schedule(1.0, f, 0.1), lambda_s=Schedule(1.0, f),
        lambda_a=Schedule(1.0, f, 0.1), n_s=Schedule(10.0, f), n_a=Schedule(3.0, f), p=Schedule(0.25, f),
        epsilon=Schedule(0.1, f, 0.01), input_init=(0.0, 1.0), epsilon_relative=True)
    text = "Table 2: four_goals (Figs. 13-15), 10x10 input, 8x1 actions, f = 1/(t/500+1), floors"
    return Preset("table2", text, config, "four_goals", "13 A, 14, 15", 20, 100)


def _table4() -> Preset:
    f = ExponentialDecay(0.999)
    config = SOMQConfig(
        input_shape=(1,), action_shape=(30,), alpha=Schedule(1.0, f, 0.05), lambda_s=Schedule(1.0, f),
        lambda_a=Schedule(1.0, f, 0.1), n_s=Schedule(0.0), n_a=Schedule(15.0, f, 2.0), p=Schedule(1.0, f, 0.5),
        epsilon=Schedule(1.0, f, 0.1))
    text = "Table 4: throw (Fig. 17), one input unit, 30x1 actions, f = 0.999^throw, floors"
    return Preset("table4", text, config, "throw", "17", 1, None, n_steps=4000)


def _table5() -> Preset:
    f = ExponentialDecay(0.9985)
    config = SOMQConfig(
        input_shape=(30,), action_shape=(30,), alpha=Schedule(1.0, f), lambda_s=Schedule(0.3, f),
        lambda_a=Schedule(1.0, f), n_s=Schedule(15.0, f), n_a=Schedule(25.0, f), p=Schedule(1.0, f),
        epsilon=Schedule(1.0, f))
    text = "Table 5: throw_distance (Figs. 21, 24 +NL/0.9985), 30x1 maps, f = 0.9985^throw"
    figures = "21, 24 (-NL: neighbourhood_q=false; -NL/0.9997: also decay=exp:0.9997)"
    return Preset("table5", text, config, "throw_distance", figures, 20, 100)


def _table7(name: str) -> Preset:
    single = name == "table7a"
    f = ExponentialDecay(0.9985 if single else 0.9997)
    config = SOMQConfig(
        input_shape=(30,) if single else (10, 10), action_shape=(30,), alpha=Schedule(1.0, f),
        lambda_s=Schedule(0.3, f), lambda_a=Schedule(1.0, f), n_s=Schedule(7.0, f), n_a=Schedule(7.0, f),
        p=Schedule(1.0, f), epsilon=Schedule(1.0, f))
    if single:
        text = "Table 7, experiment A: throw_distance (Fig. 25 A), 30x1 input, N_S = 7 f, f = 0.9985^throw"
    else:
        text = "Table 7: throw_wind/friction/mass (Fig. 25 B-D), 10x10 input, 30x1 actions, f = 0.9997^throw"
    return Preset(name, text, config, "throw_distance" if single else "throw_wind", "25", 100, 100)


def _plus(base: Preset, description: str, changes: dict[str, object]) -> Preset:
    """A paper table with changed settings, for the runs beyond the paper; named ``<table>+``."""
    return dataclasses.replace(base, name=base.name + "+", description=description,
                               config=dataclasses.replace(base.config, **changes))


def _table1_plus() -> Preset:
    base = _table1()
    return _plus(base, "Table 1 with a floor of 0.1 on lambda_A and periodic joint angles (not the paper's): "
                 "reach2 as Figs. 7-10, beyond the maps' resolution",
                 {"lambda_a": base.config.lambda_a.with_changes(floor=0.1), "periodic_actions": True})


def _table2_plus() -> Preset:
    base = _table2()
    return _plus(base, "Table 2 with periodic joint angles, the interpolated response and a slower epsilon (not "
                 "the paper's): four_goals as Figs. 13-15, without the box's edge",
                 {"periodic_actions": True, "response": "interpolated",
                  "epsilon": Schedule(0.08, InverseDecay(5000.0), base.config.epsilon.floor)})


def _table5_plus() -> Preset:
    base, f = _table5(), ExponentialDecay(0.9997)
    cfg = base.config
    return _plus(base, "Table 5 with f = 0.9997^throw and floors (not the paper's): throw_distance as Fig. 21, "
                 "beyond the maps' resolution",
                 {"alpha": Schedule(cfg.alpha.scale, f, 0.05), "lambda_s": Schedule(cfg.lambda_s.scale, f),
                  "lambda_a": Schedule(cfg.lambda_a.scale, f, 0.1), "n_s": Schedule(cfg.n_s.scale, f),
                  "n_a": Schedule(cfg.n_a.scale, f), "p": Schedule(cfg.p.scale, f),
                  "epsilon": Schedule(cfg.epsilon.scale, f, 0.02)})


def _obstacle() -> Preset:
    f = InverseDecay(5000.0)
    config = SOMQConfig(
        input_shape=(20, 20), action_shape=(5, 5), alpha=Schedule(1.0, f, 0.1), lambda_s=Schedule(1.0, f, 0.01),
        lambda_a=Schedule(0.0), n_s=Schedule(2.0, f), n_a=Schedule(0.0), p=Schedule(1.0, f, 0.2),
        epsilon=Schedule(0.5, f, 0.05), gamma=0.9, epsilon_relative=True, action_init="grid")
    text = ("beyond the paper: reach2_obstacle, gamma 0.9, 20x20 input map over the angles and the goal, "
            "a fixed 5x5 grid of target changes")
    return Preset("obstacle", text, config, "reach2_obstacle", "none (the report's delayed-reward part)", 10, 1000,
                  n_steps=500_000)


#: InvertedPendulum-v5's scaling (``tasks.gym_envs.scaling_how``): the cart's rail [-1, 1] and the
#: pole's ending angle +-0.2 instead of the random-action estimate; the cart's position widened 32
#: times, its velocity 4 and the pole's angular velocity 2 (so they count less in the map's distance).
_INVERTED_PENDULUM_SCALING = {"observation_ranges": {"0": [-1.0, 1.0], "1": [-0.2, 0.2]},
                              "observation_widened": {"0": 32.0, "2": 4.0, "3": 2.0}}


#: Reacher-v5's scaling: the joint velocities (dimensions 6 and 7) over +-5 rad/s, the range a reaching arm
#: moves in, instead of the random-action estimate (about +-20 rad/s, where a reach fills a tenth of a map);
#: the fingertip-to-target offsets (dimensions 8 and 9) over +-0.2 m instead of the estimate's about +-0.38, so the
#: maps spend their units where a reach ends rather than on offsets only random arms reach.
_REACHER_SCALING = {"observation_ranges": {"6": [-5.0, 5.0], "7": [-5.0, 5.0], "8": [-0.2, 0.2], "9": [-0.2, 0.2]}}


#: dmc:cartpole-balance's scaling: the region a balancing cart keeps to (the pole's sine within +-0.25, its
#: angular velocity +-2 rad/s, the cart within +-1.5 m and +-1.5 m/s) instead of the random-action estimate,
#: under which the pole mostly hangs and a balanced pole fills a few units of a map.
_BALANCE_SCALING = {"observation_ranges": {"0": [-1.5, 1.5], "1": [-1.0, 1.0], "2": [-0.25, 0.25],
                                           "3": [-1.5, 1.5], "4": [-2.0, 2.0]}}


#: dmc:point_mass-easy's scaling: the positions from +-3 cm (the target's 1.5 cm radius and the ring round it
#: where its reward fades), the velocities from +-0.1 m/s; farther states fall past the maps' edge units, where
#: the way to the target is the same push.
_POINT_MASS_SCALING = {"observation_ranges": {"0": [-0.03, 0.03], "1": [-0.03, 0.03], "2": [-0.1, 0.1],
                                              "3": [-0.1, 0.1]}}


#: How dmc_pendulum sees and acts on dmc:pendulum-swingup: the pole's angle (``angles``: the orientation's
#: cosine and sine as one angle, 0 upright), so that its grid's cells lie evenly round the circle; the velocity
#: over +-10 rad/s (random torques never raise the pole, so the range they see ends below the rewarded top);
#: a decision every 5 of the suite's 20 ms steps (``action_repeat``), so that each pair of cells the model
#: counts is a tenth of a second of the swing, not a step that mostly stays in its cell.
_PENDULUM_SCALING = {"angles": [[0, 1]], "action_repeat": 5, "observation_ranges": {"1": [-10.0, 10.0]}}


def _benchmark(name: str, env_id: str, changes: dict[str, object], task_params: dict | None = None) -> Preset:
    """A preset for a Gymnasium benchmark (``gym:ID``): the common recipe with ``changes``; the run
    length is the task's (``tasks.gym_envs.BENCHMARKS``), not the preset's."""
    slow = InverseDecay(20_000.0)
    config = SOMQConfig(
        input_shape=(20, 20), action_shape=(3,), alpha=Schedule(1.0, slow, 0.05),
        lambda_s=Schedule(1.0, InverseDecay(2000.0)), lambda_a=Schedule(0.0), n_s=Schedule(1.0, slow),
        n_a=Schedule(0.0), p=Schedule(0.0), epsilon=Schedule(0.0), gamma=0.98, epsilon_relative=True,
        input_init=(0.0, 1.0), response="interpolated", action_init="grid")
    return Preset(name, f"beyond the paper: gym:{env_id}, Gymnasium's benchmark", dataclasses.replace(config, **changes),
                  f"gym:{env_id}", "none (the report's benchmarks part)", 5, None, task_params=task_params or {})


def _benchmarks() -> tuple[Preset, ...]:
    fast = InverseDecay(5000.0)
    generic = _benchmark("gym", "ID", {
        "p": Schedule(1.0, fast, 0.05), "epsilon": Schedule(0.5, fast, 0.05), "action_init": "random",
        "lambda_a": Schedule(1.0, fast, 0.05), "action_shape": (9,), "n_a": Schedule(1.0, fast)})
    pendulum = _benchmark("pendulum", "Pendulum-v1", {
        "input_shape": (40, 40), "n_s": Schedule(3.0, InverseDecay(60_000.0)),
        "alpha": Schedule(1.0, InverseDecay(250_000.0), 0.05)})
    mountaincar = _benchmark("mountaincar", "MountainCarContinuous-v0", {
        "gamma": 0.99, "q_init": 30.0, "action_shape": (4,), "lambda_s": Schedule(0.0), "n_s": Schedule(0.0)})
    invertedpendulum = _benchmark("invertedpendulum", "InvertedPendulum-v5", {
        "gamma": 0.995, "q_init": 200.0, "input_groups": "1,2,3", "action_shape": (11,), "grid_span": 1.0 / 6.0,
        "n_a": Schedule(2.0, InverseDecay(20_000.0))}, _INVERTED_PENDULUM_SCALING)
    reacher = _benchmark("reacher", "Reacher-v5", {
        "gamma": 0.95, "action_shape": (3, 3), "grid_span": 0.1, "input_groups": "pairs", "input_shape": (10, 10),
        "k_nearest": 3, "local_linear": True, "shared_slopes": True, "n_a": Schedule(2.0), "n_step": 3}, _REACHER_SCALING)
    # The DeepMind Control Suite's report tasks (``tasks.gym_envs``' DMC_BENCHMARKS).
    dmc = Preset(
        "dmc", "beyond the paper: the DeepMind Control Suite's one-force tasks (the recipe of dmc_cartpole, dmc_pendulum)",
        dataclasses.replace(invertedpendulum.config, input_groups="all"),
        "dmc:cartpole-swingup", "none (the report's dmc part)", 5, None)
    balance = Preset(
        "dmc_balance", "beyond the paper: the DeepMind Control Suite's dmc:cartpole-balance",
        dataclasses.replace(invertedpendulum.config, input_groups="2,4", input_shape=(30, 30), local_linear=True,
                            shared_slopes=True, n_step=30,
                            alpha=dataclasses.replace(invertedpendulum.config.alpha, floor=0.0)),
        "dmc:cartpole-balance", "none (the report's dmc part)", 5, None, task_params=_BALANCE_SCALING)
    dmc_2d = Preset(
        "dmc_2d", "beyond the paper: the DeepMind Control Suite's two-force tasks (dmc:reacher-*, dmc:point_mass-easy)",
        dataclasses.replace(invertedpendulum.config, input_groups="all", action_shape=(3, 3), grid_span=1.0),
        "dmc:reacher-easy", "none (the report's dmc part)", 5, None)
    point_mass = Preset(
        "dmc_point_mass", "beyond the paper: the DeepMind Control Suite's dmc:point_mass-easy",
        dataclasses.replace(dmc_2d.config, input_groups="0,2;1,3", n_step=30, action_gap=0.5),
        "dmc:point_mass-easy", "none (the report's dmc part)", 5, None, task_params=_POINT_MASS_SCALING)
    swingup = Preset(
        "dmc_pendulum", "beyond the paper: the DeepMind Control Suite's dmc:pendulum-swingup",
        dataclasses.replace(dmc.config, input_shape=(30, 30), grid_span=1.0, input_placement="grid",
                            lambda_s=Schedule(0.0), gamma=0.95, q_init=100.0, plan=100, plan_every=200),
        "dmc:pendulum-swingup", "none (the report's dmc part)", 5, None, task_params=_PENDULUM_SCALING)
    cartpole = Preset(
        "dmc_cartpole", "beyond the paper: the DeepMind Control Suite's dmc:cartpole-swingup",
        dataclasses.replace(dmc.config, q_init=0.0, n_step=30, grid_span=1.0),
        "dmc:cartpole-swingup", "none (the report's dmc part)", 5, None)
    return generic, pendulum, mountaincar, invertedpendulum, reacher, dmc, balance, dmc_2d, point_mass, swingup, cartpole


def _with_choices(presets: tuple[Preset, ...]) -> dict[str, Preset]:
    """``presets`` by name, each with its choices from ``preset_choices.md`` (``somarm.learners.choices``)."""
    found = _choices.read([p.name for p in presets])
    return {p.name: dataclasses.replace(p, choices=found[p.name]) for p in presets}


PRESETS: dict[str, Preset] = _with_choices(
    (_table1(), _table2(), _table4(), _table5(), _table7("table7"), _table7("table7a"), _table1_plus(),
     _table2_plus(), _table5_plus(), _obstacle(), *_benchmarks()))


def _preset(name: str) -> Preset:
    if name not in PRESETS:
        raise ValueError(f"unknown preset {name!r}; allowed: {', '.join(PRESETS)}")
    return PRESETS[name]


def get(name: str) -> SOMQConfig:
    """The ``SOMQConfig`` of a preset (``PRESETS``); an unknown name is a ValueError listing the names."""
    return _preset(name).config


def describe(name: str) -> str:
    """One line saying which table, figure and task a preset is."""
    return _preset(name).description


def task_params_of(name: str, task: str) -> dict[str, Any]:
    """The task parameters preset ``name`` asks of ``task``: its ``task_params`` where ``task`` is its own
    task, else none (a run's own ``--task-set`` values go over them)."""
    preset = _preset(name)
    return copy.deepcopy(preset.task_params) if task == preset.task else {}


def motoric_from_somq(config: SOMQConfig) -> MotoricConfig:
    """The Motoric Map counterpart of a SOM-Q config (``MotoricConfig.from_table``)."""
    return MotoricConfig.from_table(config)


def get_motoric(name: str) -> MotoricConfig:
    """The Motoric Map config matching a table (``get_motoric("table2")`` is Fig. 13 B's); an unknown
    name is a ValueError listing the names."""
    return motoric_from_somq(get(name))


def config_for(kind: str, name: str):
    """The config of learner ``kind`` (``somarm.learners.LEARNERS``) for preset ``name``; an unknown kind
    or name is a ValueError listing what is allowed."""
    from somarm.learners import config_class

    return config_class(kind).from_table(get(name))
