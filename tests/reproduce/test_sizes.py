"""``reproduce --seeds``: each experiment's declared groups, their memory at every seed, refused before writing."""

from pathlib import Path

import pytest

from somarm import run, validation
from somarm.reproduce import common, runner, sizes
from somarm.reproduce.common import Context


class _Trained(Exception):
    """Raised by the stand-in trainer once it has seen what an experiment trains."""


#: Every part that trains lockstep groups: the default ones and the optional delayed_reward.
TRAINED = {**runner.EXPERIMENTS, "delayed_reward": runner.OPTIONAL["delayed_reward"]}


def test_every_experiment_of_the_paper_declares_its_groups_and_peers_has_none():
    assert all(sizes.groups_of(experiment) is not None for experiment in TRAINED.values())
    assert sizes.groups_of(runner.OPTIONAL["peers"]) is None


@pytest.mark.parametrize("name", list(TRAINED))
def test_an_experiment_trains_the_groups_it_declares(name, monkeypatch):
    seen = []

    def record(configs, **kwargs):
        seen.append((kwargs["label"], configs))
        raise _Trained

    monkeypatch.setattr(common, "train_group", record)
    ctx = Context(out_dir=Path("unused"), quick=True, seed=3, progress=False, seeds=(3, 4))
    with pytest.raises(_Trained):
        TRAINED[name](ctx)
    label, configs = next(iter(sizes.groups_of(TRAINED[name])(ctx).items()))  # the first group trains first
    assert seen == [(label, common.at_seeds(ctx, configs))]


@pytest.mark.parametrize("name", ["reach2", "beyond"])
def test_the_memory_at_several_seeds_is_the_estimate_of_the_groups_trained_at_all_of_them(name):
    quick = {"quick": True, "backend": "analytic"}
    what, n_bytes = sizes.memory_at_seeds(runner.EXPERIMENTS[name], seed=5, seeds=3, **quick)
    ctx = Context(out_dir=Path("unused"), seed=5, seeds=(5, 6, 7), **quick)
    groups = [run.memory_needs([c.resolved() for c in common.at_seeds(ctx, configs)])
              for configs in sizes.groups_of(runner.EXPERIMENTS[name])(ctx).values()]
    assert n_bytes == pytest.approx(sum(size for _, size in groups), rel=1e-12)
    assert n_bytes == pytest.approx(3 * sizes.memory_at_seeds(runner.EXPERIMENTS[name], seed=5, seeds=1, **quick)[1], rel=1e-12)
    assert what.count("over") == len(groups) and "trial(s)" in what


def test_seeds_that_cannot_fit_are_refused_in_one_line_before_the_report_folder_is_made(tmp_path, monkeypatch):
    monkeypatch.setattr(validation, "_available_memory", lambda: 2**30)
    out = tmp_path / "report"
    with pytest.raises(ValueError) as refused:
        runner.reproduce(out, quick=True, only=["throw", "reach2"], seeds=100_000, progress=False)
    message = str(refused.value)
    assert "\n" not in message and message.startswith("--seeds 100000 (throw: a somq learner")
    assert "needs about" in message and "more than the 1.0 GiB available; give fewer --seeds" in message
    assert not out.exists()


def test_seeds_that_fit_pass_and_the_peers_part_is_not_sized(monkeypatch):
    monkeypatch.setattr(validation, "_available_memory", lambda: 2**30)
    sizes.check_seeds(runner.EXPERIMENTS, quick=True, seed=0, seeds=2, backend="mujoco")
    sizes.check_seeds({"peers": runner.OPTIONAL["peers"]}, quick=False, seed=0, seeds=100_000, backend="mujoco")
