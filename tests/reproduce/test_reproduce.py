import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from somarm.reproduce import runner
from somarm.reproduce.report import Claim, Section, claim_record, merge_seeds, render


def test_render_lists_every_claim_and_figure(tmp_path):
    section = Section(
        "demo",
        "Demo",
        figures=[tmp_path / "figures" / "a.png"],
        claims=[Claim("It works.", "3 of 3", True, ">= 3"), Claim("It is fast.", "slow", False)],
        choices=["run length 10 (ours)"],
    )
    text = render([section], header=["hello"], out_dir=tmp_path)
    assert text.startswith("# somarm: reproduction of Smith (2002)\n\nhello\n")
    assert "| demo | It works. | 3 of 3 | >= 3 | **holds** |" in text
    assert "**does not hold**" in text and "](figures/a.png)" in text
    assert "run length 10 (ours)" in text
    odd = render([Section("x", "X", claims=[Claim("a", "mean |d| 0.3", True)])], header=[], out_dir=tmp_path)
    assert "| x | a | mean \\|d\\| 0.3 |  | **holds** |" in odd


def _check_report(out: Path, names: list[str]) -> dict:
    report = (out / "REPORT.md").read_text()
    claims = runner.load_claims(out)
    assert claims["complete"] is True and claims["quick"] is True
    assert sorted(claims["experiments"]) == sorted(names)
    for name in names:
        entries = claims["experiments"][name]["claims"]
        assert entries, f"{name} states no claim"
        for entry in entries:
            # The report's row for this claim shows the verdict claims.json records.
            verdict = {True: "holds", False: "does not hold", None: "undecided"}[entry["holds"]]
            rows = [line for line in report.splitlines() if line.startswith(f"| {name} | ")
                    and entry["claim"].replace("|", "\\|") in line]
            assert rows and all(line.rstrip().endswith(f"**{verdict}** |") for line in rows), (name, entry["claim"])
            assert re.search(r"\d", entry["measured"]), f"{name}: no number measured"
    for link in re.findall(r"!\[[^\]]*\]\(([^)]+)\)", report):
        path = out / link
        assert path.is_file() and path.stat().st_size > 10_000, f"missing or empty figure {link}"
    assert "this project's choice" in report
    return claims


def test_quick_reproduce_end_to_end_smoke(tmp_path):
    names = ["throw", "four_goals"]
    assert runner.reproduce(tmp_path, quick=True, only=names, progress=False) == 0
    _check_report(tmp_path, names)


def test_quick_reproduce_every_experiment(tmp_path):
    # The whole quick path (about a minute): every experiment runs, reports numbers and draws its figures.
    assert runner.reproduce(tmp_path, quick=True, progress=False) == 0
    _check_report(tmp_path, list(runner.EXPERIMENTS))


def test_unknown_experiment_lists_the_names(tmp_path):
    with pytest.raises(ValueError, match="allowed: reach2"):
        runner.reproduce(tmp_path, quick=True, only=["fig99"])


def test_ctrl_c_stops_the_whole_reproduction_and_keeps_finished_parts(tmp_path):
    # In this process (--jobs 1): reach2 (quick) finishes in seconds; the signal arrives during the much longer throw_maps.
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "somarm.cli",
            "reproduce",
            "--quick",
            "--no-progress",
            "--jobs",
            "1",
            "--out",
            str(tmp_path),
            "--only",
            "reach2",
            "throw_maps",
            "more_inputs",
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env={**os.environ, "MUJOCO_GL": "disable"},
    )
    try:
        deadline = time.monotonic() + 120
        line = ""
        while not line.startswith("reach2:") and time.monotonic() < deadline:
            line = proc.stderr.readline()
        time.sleep(0.3)
        proc.send_signal(signal.SIGINT)
        _, err = proc.communicate(timeout=120)
    finally:
        proc.kill()
    assert proc.returncode == 130, err
    claims = runner.load_claims(tmp_path)
    assert claims["complete"] is False and list(claims["experiments"]) == ["reach2"]
    assert "Incomplete" in (tmp_path / "REPORT.md").read_text()


def test_merged_seeds_say_in_how_many_seeds_a_claim_holds(tmp_path):
    parts = [Section("demo", "Demo", claims=[Claim("It works.", f"error {e}", e < 0.5, "error < 0.5",
                                                   values={"error": e})]) for e in (0.3, 0.7, 0.4)]
    merged = merge_seeds(parts, [4, 5, 6])
    claim = merged.claims[0]
    assert claim.verdict() == "holds in 2 of 3 seeds" and claim.holds is None
    assert "error: 0.3, 0.7, 0.4 (range 0.3 to 0.7" in claim.spread()
    record = claim_record(claim)
    assert record["holds_in"] == 2 and record["seeds"] == 3
    assert [s["seed"] for s in record["per_seed"]] == [4, 5, 6]
    assert record["spread"]["error"]["min"] == 0.3 and record["spread"]["error"]["max"] == 0.7
    assert "**holds in 2 of 3 seeds**" in render([merged], header=[], out_dir=tmp_path)
    with pytest.raises(ValueError, match="different claims"):
        merge_seeds([parts[0], Section("demo", "Demo")], [0, 1])


def test_counts_are_listed_at_every_seed_with_their_sum(tmp_path):
    parts = [Section("demo", "Demo", claims=[Claim("It works.", "yes", True)], counts={"failed trials": n})
             for n in (1, 0, 3)]
    merged = merge_seeds(parts, [4, 5, 6])
    assert merged.counts == {"failed trials": [1.0, 0.0, 3.0]}
    text = render([merged], header=[], out_dir=tmp_path, seeds=[4, 5, 6])
    assert "- failed trials: 1, 0, 3 at seeds 4 to 6, 4 in all" in text
    alone = render([parts[2]], header=[], out_dir=tmp_path)
    assert "- failed trials: 3" in alone and "in all" not in alone


def test_several_seeds_in_lockstep_equal_single_seed_runs(tmp_path):
    # Seed 1 trained beside seed 0 (one group, one physics call per step) gives the numbers of a
    # reproduction at seed 1 alone. The closed forms keep this test short (test_training checks
    # lockstep groups through MuJoCo); the report names the backend.
    quick = {"quick": True, "only": ["throw"], "backend": "analytic", "progress": False}
    assert runner.reproduce(tmp_path / "two", seeds=2, **quick) == 0
    assert runner.reproduce(tmp_path / "one", seed=1, **quick) == 0
    two = runner.load_claims(tmp_path / "two")
    one = runner.load_claims(tmp_path / "one")
    assert two["seeds"] == [0, 1] and one["seeds"] == [1] and two["backend"] == "analytic"
    for merged, alone in zip(two["experiments"]["throw"]["claims"], one["experiments"]["throw"]["claims"],
                             strict=True):
        assert merged["seeds"] == 2 and [s["seed"] for s in merged["per_seed"]] == [0, 1]
        assert merged["per_seed"][1]["values"] == alone["values"]
        assert merged["per_seed"][1]["measured"] == alone["measured"]
        assert merged["holds_in"] == sum(s["holds"] is True for s in merged["per_seed"])
    report = (tmp_path / "two" / "REPORT.md").read_text()
    assert "of 2 seeds**" in report and "Over seeds:" in report
    assert "closed forms (backend `analytic`" in report


def test_bad_backend_or_seed_count_fails_in_one_line(tmp_path):
    with pytest.raises(ValueError, match="unknown backend 'bullet'; allowed: mujoco, analytic"):
        runner.reproduce(tmp_path, quick=True, only=["throw"], backend="bullet")
    with pytest.raises(ValueError, match="seeds must be a whole number >= 1"):
        runner.reproduce(tmp_path, quick=True, only=["throw"], seeds=0)
