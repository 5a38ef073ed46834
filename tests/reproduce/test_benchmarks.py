import pytest

from somarm.peers import compare
from somarm.reproduce import benchmarks
from somarm.reproduce.benchmarks import ReportSeeds
from somarm.reproduce.common import Context


def _measured(env_id, somq, somq_plus, td3, sac, final=-7.0):
    learners = benchmarks.LEARNERS
    finals = {k: (-3.9 if k in ("td3", "sac") else final, 0.5) for k in learners}
    to_target = {**{k: None for k in learners}, "somq": somq, "somq+": somq_plus, "td3": td3, "sac": sac}
    return {env_id: {"final": finals, "seeds": {k: 10 if k.startswith("somq") else 5 for k in learners},
                     "random": -43.0, "converged": -3.9, "to_target": to_target}}


def test_each_response_has_its_own_target_and_speed_claim_measured_against_the_faster_peer():
    m = _measured("Reacher-v5", (50_000, 30.0), (20_000, 70.0), (20_000, 326.0), (20_000, 200.0), final=-5.5)
    claims = benchmarks._claims(m)
    assert [c.holds for c in claims] == [True, True, True, False]  # 30 x 5 <= 200; 70 x 5 > 200
    assert "SOM-Q ends at -5.5 ± 0.5 over 10 seeds" in claims[0].measured
    assert "SOM-Q+ (interpolated)" in claims[1].claim
    # samples beside seconds, for SOM-Q and for the faster peer (SAC here, not TD3)
    assert claims[2].measured.startswith("SOM-Q: 50000 samples, 30")
    assert "the faster peer, SB3 SAC: 20000 samples, 200" in claims[2].measured


def test_a_speed_claim_without_a_peer_at_the_target_has_no_verdict_and_one_short_of_it_fails():
    m = _measured("Reacher-v5", None, None, None, None)
    assert [c.holds for c in benchmarks._claims(m)] == [False, False, None, None]
    m = _measured("Reacher-v5", None, (20_000, 10.0), (20_000, 326.0), None)
    assert [c.holds for c in benchmarks._claims(m)][2:] == [False, True]


def test_report_seeds_are_consecutive_ranges_that_never_touch_the_tuning_seeds():
    seeds = ReportSeeds(range(10, 20), range(0, 5))
    assert "seeds 10-19" in seeds.text() and "seeds 0-4" in seeds.text() and "100-199" in seeds.text()
    assert ReportSeeds.same(0, 5).text().startswith("Seeds 0-4 for every learner")
    with pytest.raises(ValueError, match="overlap the tuning seeds 100-199"):
        ReportSeeds(range(95, 105), range(0, 5))
    with pytest.raises(ValueError, match="peers seeds must be a range of consecutive seeds"):
        ReportSeeds(range(0, 5), range(0, 10, 2))


def test_the_part_trains_each_side_on_its_own_seeds_and_scores_all_on_the_same_episodes(tmp_path, monkeypatch):
    calls = []

    def fake(config, out, *, progress, resume):
        calls.append(config)
        out.mkdir(parents=True, exist_ok=True)
        seeds = list(range(config.seed, config.seed + config.seeds))
        rows = [[-5.0] * len(seeds)]
        return {"task": config.task, "seeds": seeds, "task_params": {}, "random_action_return": -43.0,
                "learners": {k: {"samples": [100], "return": rows, "wall_seconds": [[1.0] * len(seeds)],
                                 "seconds_per_sample": [0.01] * len(seeds), "settings": {}} for k in config.learners}}

    monkeypatch.setattr(compare, "compare", fake)
    monkeypatch.setattr(benchmarks, "compare_figure", lambda result, path: None)
    ctx = Context(out_dir=tmp_path, seed=0, progress=False)
    results = benchmarks.train(ctx, ReportSeeds(range(10, 20), range(0, 5)), 100, ("Reacher-v5",))
    ours, *rest = calls
    assert ours.learners == ("somq", "somq+") and (ours.seed, ours.seeds, ours.eval_seed) == (10, 10, 0)
    # the baselines (no tabular on Reacher-v5) and each peer on the peers' seeds
    assert [p.learners for p in rest] == [("motoric",), ("td3",), ("sac",)]
    assert [(p.seed, p.seeds, p.eval_seed) for p in rest] == [(0, 5, 0)] * 3
    merged = results["Reacher-v5"]
    assert merged["learners"]["somq"]["seeds"] == list(range(10, 20))
    assert merged["learners"]["td3"]["seeds"] == list(range(5))
    assert benchmarks.measure(results)["Reacher-v5"]["seeds"] == {"somq": 10, "somq+": 10, "motoric": 5,
                                                                  "td3": 5, "sac": 5}
