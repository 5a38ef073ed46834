import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from somarm.reproduce import runner
from somarm.reproduce.report import Claim, Section, render


def test_render_lists_every_claim_and_figure(tmp_path):
    section = Section(
        "demo",
        "Demo",
        figures=[tmp_path / "figures" / "a.png"],
        claims=[Claim("It works.", "3 of 3", True, ">= 3"), Claim("It is fast.", "slow", False)],
        choices=["run length 10 (ours)"],
    )
    text = render([section], header=["hello"], out_dir=tmp_path)
    assert "| demo | It works. | 3 of 3 | >= 3 | **holds** |" in text
    assert "**does not hold**" in text and "![a](figures/a.png)" in text
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
            assert entry["holds"] in (True, False, None)
            assert re.search(r"\d", entry["measured"]), f"{name}: no number measured"
            assert entry["claim"].split(":")[0] in report
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
    # reach2 (quick) finishes in seconds; the signal arrives during the much longer throw_maps.
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "somarm.cli",
            "reproduce",
            "--quick",
            "--no-progress",
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
        time.sleep(1.0)
        proc.send_signal(signal.SIGINT)
        _, err = proc.communicate(timeout=120)
    finally:
        proc.kill()
    assert proc.returncode == 130, err
    claims = runner.load_claims(tmp_path)
    assert claims["complete"] is False and list(claims["experiments"]) == ["reach2"]
    assert "Incomplete" in (tmp_path / "REPORT.md").read_text()
