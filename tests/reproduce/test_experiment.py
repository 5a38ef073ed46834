"""``reproduce.experiment.Experiment``: every experiment of the paper fills in the one shape."""

from pathlib import Path

import pytest

from somarm.reproduce import runner, sizes
from somarm.reproduce.common import Context, at_seeds
from somarm.reproduce.experiment import Experiment
from somarm.reproduce.report import Section


@pytest.mark.parametrize("name", [*runner.EXPERIMENTS, "delayed_reward"])
def test_every_experiment_of_the_paper_is_an_experiment_with_its_groups(name):
    experiment = {**runner.EXPERIMENTS, **runner.OPTIONAL}[name]
    assert isinstance(experiment, Experiment)
    assert sizes.groups_of(experiment) is experiment.groups
    groups = experiment.groups(Context(out_dir=Path(), quick=True, progress=False, figures=False))
    assert groups and all(configs for configs in groups.values())


def test_an_experiment_reports_what_it_trained_in_its_own_backend():
    seen = {}

    def train(ctx):
        seen["train"] = ctx.backend
        return 7

    def report(ctx, trained):
        seen["report"] = (ctx.backend, trained)
        return Section("x", "X")

    section = Experiment(lambda ctx: {}, train, report, backend="mujoco")(Context(out_dir=Path(), backend="analytic"))
    assert section.name == "x" and seen == {"train": "mujoco", "report": ("mujoco", 7)}
    Experiment(lambda ctx: {}, train, report)(Context(out_dir=Path(), backend="analytic"))
    assert seen["train"] == "analytic"


def test_the_driven_arm_trains_in_mujoco_under_the_analytic_backend():
    driven = runner.EXPERIMENTS["driven_arm"]
    ctx = driven.context(Context(out_dir=Path(), quick=True, backend="analytic"))
    configs = [c for group in driven.groups(ctx).values() for c in at_seeds(ctx, group)]
    assert {c.backend for c in configs} == {"mujoco"}
    # the run's check before anything is written passes (it used to fail once the folder was claimed)
    assert runner.check_request(["driven_arm"], quick=True, seed=0, seeds=1, jobs=1, backend="analytic") == ["driven_arm"]
