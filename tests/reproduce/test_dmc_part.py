"""The report part ``dmc``: which learner trains on which seeds, the target claims, and a quick run end to end."""

import pytest

from somarm.peers import compare
from somarm.reproduce import benchmarks, dmc
from somarm.reproduce.benchmarks import ReportSeeds
from somarm.reproduce.common import Context


def _fake_compare(calls):
    def fake(config, out, *, progress, resume):
        calls.append(config)
        out.mkdir(parents=True, exist_ok=True)
        seeds = list(range(config.seed, config.seed + config.seeds))
        return {"task": config.task, "seeds": seeds, "task_params": {}, "random_action_return": 3.0,
                "learners": {k: {"samples": [100], "return": [[500.0] * len(seeds)], "wall_seconds": [[1.0] * len(seeds)],
                                 "seconds_per_sample": [0.01] * len(seeds), "settings": {}} for k in config.learners}}
    return fake


@pytest.fixture
def faked(tmp_path, monkeypatch):
    calls = []
    monkeypatch.setattr(compare, "compare", _fake_compare(calls))
    monkeypatch.setattr(benchmarks, "compare_figure", lambda result, path: None)
    return calls, Context(out_dir=tmp_path, seed=0, progress=False)


def test_somarms_learners_train_on_the_fresh_seeds_and_each_peer_alone_on_its_own(faked):
    calls, ctx = faked
    results = dmc.train(ctx, dmc.SEEDS, 100, ("dmc:cartpole-balance",))
    assert [c.learners for c in calls] == [("somq", "somq+"), ("td3",), ("sac",)]
    assert [(c.seed, c.seeds) for c in calls] == [(30, 5), (0, 5), (0, 5)]  # dmc_balance's fresh seeds
    assert all(c.task == "dmc:cartpole-balance" and c.eval_seed == 0 for c in calls)
    assert calls[1].peer_samples == dmc.PEER_SAMPLES and calls[0].peer_samples is None
    merged = results["dmc:cartpole-balance"]
    assert merged["learners"]["somq"]["seeds"] == list(range(30, 35))
    assert merged["learners"]["sac"]["seeds"] == list(range(5))


def test_a_recorded_report_reads_each_group_at_its_recorded_seeds_and_trains_none(faked):
    calls, ctx = faked
    folder = ctx.out_dir / "dmc" / "cartpole-balance"
    for group, kinds, seeds in (("sac", ("sac",), (0, 1, 3)), ("somq-somq+", ("somq", "somq+"), (30, 31, 32))):
        (folder / group / "seeds").mkdir(parents=True)
        for kind in kinds:
            for seed in seeds:  # sac's seed 2 is missing: its recorded seeds stop at 1
                (folder / group / "seeds" / f"{kind}-{seed}.json").write_text("{}")
    (folder / "somq-somq+" / "seeds" / "somq+-32.json").unlink()  # both responses are needed at a seed
    results = dmc.train(ctx, dmc.SEEDS, 100, ("dmc:cartpole-balance", "dmc:reacher-easy"), recorded=True)
    assert [(c.learners, c.seed, c.seeds) for c in calls] == [(("somq", "somq+"), 30, 2), (("sac",), 0, 2)]
    assert list(results) == ["dmc:cartpole-balance"]  # no record of reacher-easy: left out
    m = dmc.measure(results)
    assert m["dmc:cartpole-balance"]["seeds"]["sac"] == [0, 1] and "td3" not in m["dmc:cartpole-balance"]["seeds"]
    missing = dmc._missing(m, dmc.SEEDS, ("dmc:cartpole-balance", "dmc:reacher-easy"))
    assert "- dmc:reacher-easy: no seed recorded" in missing
    assert any("SB3 TD3 at 0 of 5 seeds" in line for line in missing)
    assert any("SOM-Q at 2 of 5 seeds (seeds 30-31 recorded)" in line for line in missing)
    claims = dmc._claims(m)
    assert [c.holds for c in claims if "point_mass" in c.claim] == [None, None]


def _measured(somq, sac):
    final = {"somq": (somq, 5.0), "somq+": (somq, 5.0)}
    seeds = {"somq": list(range(10, 15)), "somq+": list(range(10, 15))}
    if sac is not None:
        final["sac"], seeds["sac"] = (sac, 2.0), [0, 1]
    budget = {kind: 100_000 for kind in final}
    return {task: {"final": final, "seeds": seeds, "budget": budget, "sac": sac, "random": 1.0}
            for task in dmc.TARGET_TASKS}


@pytest.mark.parametrize("somq, sac, holds", [(950.0, 1000.0, True), (899.0, 1000.0, False), (900.0, 1000.0, True),
                                               (500.0, None, None)])
def test_the_target_is_90_percent_of_sacs_final_return_and_undecided_without_sac(somq, sac, holds):
    claims = dmc._claims(_measured(somq, sac))
    assert len(claims) == 2 * len(dmc.TARGET_TASKS)
    assert all(c.holds is holds for c in claims)
    if sac is None:
        assert "no SAC seed is recorded" in claims[0].measured


def test_report_seeds_of_the_part_are_fresh_and_a_changed_preset_takes_seeds_its_task_was_never_scored_on():
    assert list(dmc.SEEDS) == list(dmc.TASKS)
    for seeds in dmc.SEEDS.values():
        assert isinstance(seeds, ReportSeeds)
        assert not set(seeds.ours) & set(range(100, 200)) and not set(seeds.peers) & set(range(100, 200))
    assert dmc.SEEDS["dmc:cartpole-balance"].ours == range(30, 35) and dmc.SEEDS["dmc:reacher-easy"].ours == range(10, 15)
    assert dmc.SEEDS["dmc:point_mass-easy"].ours == range(40, 45)
    assert dmc.SEEDS["dmc:pendulum-swingup"].ours == range(40, 45)


def test_a_report_of_the_suite_alone_is_titled_and_sourced_as_the_suites():
    from somarm.reproduce import report, runner
    from somarm.reproduce.report import Section

    sections = [Section("dmc_recorded", "The DeepMind Control Suite")]
    header = runner._header(sections, quick=True, seeds=[0], backend="mujoco", total=1.0, complete=True,
                            benchmarks_only=True, suite_only=True)
    assert "DeepMind Control Suite's own tasks" in header[0] and "Gymnasium's own environment" not in header[0]
    assert report.SUITE_TITLE != report.BENCHMARKS_TITLE


def _learner(samples, returns, seeds):
    return {"samples": samples, "return": returns, "seeds": seeds, "seconds_per_sample": [1e-3] * len(seeds),
            "wall_seconds": [[0.1 * s] * len(seeds) for s in samples]}


def test_claims_name_each_sides_samples_and_the_peers_last_rungs_are_reported():
    results = {"dmc:point_mass-easy": {"random_action_return": 1.0, "learners": {
        "somq": _learner([100, 300], [[1.0, 3.0], [85.0, 95.0]], [30, 31]),
        "somq+": _learner([100, 300], [[1.0, 3.0], [70.0, 80.0]], [30, 31]),
        "sac": _learner([50, 100], [[10.0, 30.0], [100.0, 100.0]], [0, 1])}}}
    m = dmc.measure(results)
    assert m["dmc:point_mass-easy"]["before_last"]["sac"] == (50, 20.0)
    claims = {c.claim.split(" reaches")[0].split(": ")[1]: c for c in dmc._claims(m)
              if "point_mass" in c.claim}
    assert claims["SOM-Q"].holds is True and claims["SOM-Q+ (interpolated)"].holds is False  # 90 >= 90 > 75
    assert "after 300 samples" in claims["SOM-Q"].measured and "after 100 samples" in claims["SOM-Q"].measured
    assert dmc._trend(m)[2:] == ["- dmc:point_mass-easy: SB3 SAC 20.0 at 50 samples, 100.0 at 100"]


def test_the_share_counts_as_reached_only_from_the_rung_it_is_held_to_the_end():
    early = _learner([100, 200, 300, 400], [[30.0, 30.0], [5.0, 5.0], [25.0, 25.0], [30.0, 30.0]], [0, 1])
    assert benchmarks.reach(early, 20.0, held=True) == (300, 30.0)  # 100 passes, 200 drops back: not reached there
    lost = _learner([100, 200], [[30.0, 30.0], [5.0, 5.0]], [0, 1])
    assert benchmarks.reach(lost, 20.0, held=True) is None
    kept = _learner([100, 200], [[30.0, 30.0], [25.0, 25.0]], [0, 1])
    assert benchmarks.reach(kept, 20.0, held=True) == (100, 10.0)


def test_the_hold_is_replayed_on_the_comparisons_own_episodes_and_the_report_counts_the_seeds_above_it(faked):
    calls, _ = faked
    ctx = Context(out_dir=faked[1].out_dir, seed=3, progress=False, quick=True)
    dmc.train(ctx, dmc.SEEDS, 3, ("dmc:pendulum-swingup",))  # the configs the comparisons really run with
    assert dmc.replayed(ctx, 3, ("dmc:cartpole-balance",)) == {}  # a task without a replayed controller
    replays = dmc.replayed(ctx, 3, ("dmc:pendulum-swingup",))
    score = compare.make_plan(calls[0]).scorer()
    try:
        from somarm.reproduce.yardsticks import pendulum_hold
        def hold(x):
            return pendulum_hold(score.task.unscale(x))
        assert (score(hold), score(hold, last=False)) == replays["dmc:pendulum-swingup"]
    finally:
        score.task.close()

    data = {"final": {"somq": (1.0, 0.5), "somq+": (40.0, 1.0), "sac": (30.0, 1.0)},
            "per_seed": {"somq": [1.0, 1.5], "somq+": [0.5, 99.5], "sac": [98.8, 1.0]}, "random": 0.8}
    line = next(x for x in dmc._standing({"dmc:pendulum-swingup": data}, {"dmc:pendulum-swingup": (99.1, 329.0)})
                if x.startswith("- dmc:pendulum-swingup"))
    assert "earns 99.1 on the same episodes (329.0 on the fifth of them the earlier rungs score), and 1 seed of 6 ends above it" in line
    assert "SB3 SAC 98.8, 1.0" in line and "Holding the pole only where" in line
    # SOM-Q+'s 40.0 beside both published SAC means, at the peers' budget and at 1,000,000 steps
    assert "the published SAC mean at 100000 steps 96.0, of which it is 42%; at 1000000 steps 353.6, of which it is 11%" in line
    assert any("and no seed ends above it" in x for x in dmc._standing({"dmc:pendulum-swingup": data}, {"dmc:pendulum-swingup": (100.0, 0.0)}))
    assert any("and 2 seeds of 6 end above it" in x for x in dmc._standing({"dmc:pendulum-swingup": data}, {"dmc:pendulum-swingup": (50.0, 0.0)}))
