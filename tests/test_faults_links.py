"""Links planted in run, sweep and comparison folders, on real processes: somarm replaces a link to
a file where it writes, refuses a link to a folder in one line, and never writes through either."""

from __future__ import annotations

import json
import os
import subprocess
from pathlib import Path

import pytest
from processes import checkout_env, one_error_line, somarm_command


def somarm(*argv: str, timeout: float = 120) -> subprocess.CompletedProcess:
    return subprocess.run(somarm_command(*argv), capture_output=True, text=True, env=checkout_env(),
                          timeout=timeout)


def _victim(tmp_path: Path, name: str = "victim.txt") -> Path:
    """A file outside every somarm folder, which no run may change."""
    victim = tmp_path / "elsewhere" / name
    victim.parent.mkdir(exist_ok=True)
    victim.write_text("the user's own file\n")
    return victim


def _plant_links(tmp_path: Path, planted: list[Path]) -> list[Path]:
    """Each written file of ``planted`` replaced by a link to a victim of its own; the victims."""
    victims = [_victim(tmp_path, f"victim{k}.txt") for k in range(len(planted))]
    for link, victim in zip(planted, victims, strict=True):
        link.unlink()
        link.symlink_to(victim)
    return victims


COMPARE = ("compare", "throw_distance", "--learners", "tabular", "--samples", "200", "--seeds", "1",
           "--observations", "10", "--no-progress", "--resume")


def test_a_resumed_comparison_replaces_planted_links_and_leaves_their_targets(tmp_path):
    out = tmp_path / "cmp"
    assert somarm(*COMPARE, "--out", str(out)).returncode == 0
    planted = [out / name for name in ("seeds/tabular-0.json", "compare.json", "compare.png")]
    victims = _plant_links(tmp_path, planted)
    done = somarm(*COMPARE, "--out", str(out))
    assert done.returncode == 0 and "Traceback" not in done.stderr, done.stderr
    assert all(victim.read_text() == "the user's own file\n" for victim in victims)
    assert all(not link.is_symlink() and link.stat().st_size > 0 for link in planted)
    assert json.loads((out / "compare.json").read_text())["complete"]


def test_a_comparison_whose_seeds_folder_is_a_link_is_refused_and_writes_nothing_there(tmp_path):
    out = tmp_path / "cmp"
    out.mkdir()
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    (out / "seeds").symlink_to(elsewhere)
    one_error_line(somarm(*COMPARE, "--out", str(out)), str(out / "seeds"), "symbolic link")
    assert list(elsewhere.iterdir()) == []


SWEEP = ("sweep", "reach2", "--grid", "alpha=0.1,0.2", "--steps", "100", "--no-progress", "--no-figures")


def test_a_sweep_run_again_replaces_planted_links_and_leaves_their_targets(tmp_path):
    out = tmp_path / "sweep"
    assert somarm(*SWEEP, "--out", str(out)).returncode == 0
    planted = [out / "results.csv", out / "best.json"]
    victims = _plant_links(tmp_path, planted)
    done = somarm(*SWEEP, "--out", str(out))
    assert done.returncode == 0 and "Traceback" not in done.stderr, done.stderr
    assert all(victim.read_text() == "the user's own file\n" for victim in victims)
    assert not any(link.is_symlink() for link in planted)


def test_a_sweep_json_that_is_a_link_is_refused_as_another_sweep_and_its_target_left(tmp_path):
    out = tmp_path / "sweep"
    assert somarm(*SWEEP, "--out", str(out)).returncode == 0
    victim = _victim(tmp_path)
    (out / "sweep.json").unlink()
    (out / "sweep.json").symlink_to(victim)
    one_error_line(somarm(*SWEEP, "--out", str(out)), "holds another sweep")
    assert victim.read_text() == "the user's own file\n"


def test_a_sweep_whose_points_folder_is_a_link_is_refused_and_writes_nothing_there(tmp_path):
    out = tmp_path / "sweep"
    assert somarm(*SWEEP, "--out", str(out)).returncode == 0
    elsewhere = tmp_path / "elsewhere"
    os.rename(out / "points", elsewhere)
    (out / "points").symlink_to(elsewhere)
    before = sorted(p.name for p in elsewhere.iterdir())
    one_error_line(somarm(*SWEEP[:3], "alpha=0.1,0.3", *SWEEP[4:], "--out", str(out)), "symbolic link")
    assert sorted(p.name for p in elsewhere.iterdir()) == before


TRAIN = ("train", "reach2", "--steps", "100", "--no-progress", "--no-figures")


@pytest.mark.parametrize("planted", [".somarm.lock", ".somarm-manifest.json.tmp"])
def test_a_link_at_a_run_folders_bookkeeping_is_never_written_through(tmp_path, planted):
    out = tmp_path / "run"
    assert somarm(*TRAIN, "--out", str(out)).returncode == 0
    victim = _victim(tmp_path)
    (out / planted).unlink(missing_ok=True)
    (out / planted).symlink_to(victim)
    done = somarm(*TRAIN, "--force", "--out", str(out))
    assert "Traceback" not in done.stderr, done.stderr
    if done.returncode:
        one_error_line(done, planted, "symbolic link")
    assert victim.read_text() == "the user's own file\n"


@pytest.mark.parametrize("planted", [".somarm-new", ".somarm-old"])
def test_a_link_at_a_run_folders_staging_is_removed_and_its_target_left(tmp_path, planted):
    out = tmp_path / "run"
    assert somarm(*TRAIN, "--out", str(out)).returncode == 0
    victim = _victim(tmp_path, "learner.npz")
    (out / planted).symlink_to(victim.parent)
    done = somarm(*TRAIN, "--force", "--out", str(out))
    assert done.returncode == 0 and "Traceback" not in done.stderr, done.stderr
    assert sorted(p.name for p in victim.parent.iterdir()) == ["learner.npz"]
    assert victim.read_text() == "the user's own file\n" and (out / "learner.npz").stat().st_size > 1000


def test_train_force_replaces_planted_links_and_leaves_their_targets(tmp_path):
    out = tmp_path / "run"
    assert somarm(*TRAIN, "--out", str(out)).returncode == 0
    planted = [out / name for name in ("learner.npz", "config.json", "summary.json")]
    victims = _plant_links(tmp_path, planted)
    done = somarm(*TRAIN, "--force", "--out", str(out))
    assert done.returncode == 0, done.stderr
    assert all(victim.read_text() == "the user's own file\n" for victim in victims)
    assert not any(link.is_symlink() for link in planted)


def test_a_report_whose_figures_folder_is_a_link_is_refused_and_writes_nothing_there(tmp_path):
    from somarm.reproduce import runner

    out = tmp_path / "report"
    out.mkdir()
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    (out / "figures").symlink_to(elsewhere)
    with pytest.raises(ValueError, match="figures is a symbolic link"):
        runner.reproduce(out, quick=True, only=["reach2"], progress=False)
    assert list(elsewhere.iterdir()) == []


def test_a_resumed_folder_holding_a_link_to_a_folder_is_refused_in_one_line(tmp_path):
    out = tmp_path / "cmp"
    assert somarm(*COMPARE, "--out", str(out)).returncode == 0
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    (out / "seeds" / "more").symlink_to(elsewhere)
    one_error_line(somarm(*COMPARE, "--out", str(out)), str(out / "seeds" / "more"), "symbolic link to a folder")
    assert list(elsewhere.iterdir()) == []
