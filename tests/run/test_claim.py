"""Claimed folders: one writer, a manifest of what a run wrote, a forced run swapped in only when complete."""

from __future__ import annotations

import json
import os
from pathlib import Path

import pytest

from somarm.run import claim as claim_module
from somarm.run.claim import MANIFEST_NAME, claim


def _write(root: Path, files: dict[str, str]) -> None:
    for name, text in files.items():
        (root / name).parent.mkdir(parents=True, exist_ok=True)
        (root / name).write_text(text)


def _listing(folder: Path) -> dict[str, str]:
    return {str(p.relative_to(folder)): p.read_text() for p in sorted(folder.rglob("*"))
            if p.is_file() and not p.relative_to(folder).parts[0].startswith(".somarm")}


def _first_run(folder: Path, files: dict[str, str]) -> None:
    owner = claim(folder)
    assert owner.staged and not owner.replacing and owner.path != folder
    _write(owner.path, files)
    owner.commit()
    owner.release()


def test_a_first_run_is_staged_then_moved_in_and_lists_what_it_wrote(tmp_path):
    out = tmp_path / "run"
    _first_run(out, {"config.json": "old", "figures/a.png": "A"})
    assert json.loads((out / MANIFEST_NAME).read_text())["files"] == ["config.json", "figures/a.png"]


def test_a_forced_run_replaces_only_what_the_earlier_run_wrote(tmp_path):
    out = tmp_path / "run"
    _first_run(out, {"config.json": "old", "old.png": "O", "figures/a.png": "A"})
    _write(out, {"photo.png": "mine", "figures/notes.txt": "mine too"})
    owner = claim(out, force=True)
    assert owner.staged and owner.replacing and owner.path != out
    _write(owner.path, {"config.json": "new", "new.png": "N"})
    assert _listing(out)["config.json"] == "old"  # nothing changes before commit
    owner.commit()
    owner.release()
    assert _listing(out) == {"config.json": "new", "new.png": "N", "photo.png": "mine",
                             "figures/notes.txt": "mine too"}
    assert json.loads((out / MANIFEST_NAME).read_text())["files"] == ["config.json", "new.png"]


def test_an_emptied_figures_folder_of_the_earlier_run_goes_with_it(tmp_path):
    out = tmp_path / "report"
    _first_run(out, {"REPORT.md": "old", "figures/a.png": "A"})
    owner = claim(out, force=True)
    _write(owner.path, {"REPORT.md": "new"})
    owner.commit()
    assert not (out / "figures").exists() and (out / "REPORT.md").read_text() == "new"


def test_a_forced_run_that_never_commits_leaves_the_earlier_run(tmp_path):
    out = tmp_path / "run"
    _first_run(out, {"config.json": "old"})
    owner = claim(out, force=True)
    _write(owner.path, {"config.json": "half"})
    owner.release()  # as a killed process would: the lock goes, the staging folder stays
    assert _listing(out) == {"config.json": "old"}
    again = claim(out, force=True)  # the leftover staging folder is dropped
    assert not any(again.path.iterdir())
    again.release()


def test_a_swap_cut_short_is_undone_by_the_next_claim(tmp_path, monkeypatch):
    out = tmp_path / "run"
    _first_run(out, {"config.json": "old", "a.png": "A"})
    owner = claim(out, force=True)
    _write(owner.path, {"config.json": "new", "b.png": "B"})
    real_replace = os.replace

    def dies_at_the_manifest(src, dst):
        if Path(dst).name == MANIFEST_NAME and Path(src).parent == owner.path:
            raise KeyboardInterrupt  # killed between the file moves and the commit point
        return real_replace(src, dst)

    monkeypatch.setattr(claim_module.os, "replace", dies_at_the_manifest)
    with pytest.raises(KeyboardInterrupt):
        owner.commit()
    monkeypatch.setattr(claim_module.os, "replace", real_replace)
    owner.release()
    again = claim(out, force=True)
    again.release()
    assert _listing(out) == {"config.json": "old", "a.png": "A"}


def test_a_file_named_as_out_and_a_locked_folder_are_one_line(tmp_path):
    (tmp_path / "file").write_text("x")
    with pytest.raises(ValueError, match=r"^--out .*file is a file; give a folder"):
        claim(tmp_path / "file")
    held = claim(tmp_path / "run")
    with pytest.raises(ValueError, match="being written by another somarm process"):
        claim(tmp_path / "run", force=True)
    held.release()


def test_a_resumed_run_lists_its_own_files_not_a_users_file_added_between(tmp_path):
    out = tmp_path / "sweep"
    _first_run(out, {"results.csv": "1"})
    _write(out, {"notes.txt": "mine"})
    owner = claim(out, resume=True)
    assert not owner.staged and owner.path == out
    _write(out, {"results.csv": "1,2", "points/b.json": "B"})
    owner.commit()
    owner.release()
    assert json.loads((out / MANIFEST_NAME).read_text())["files"] == ["points/b.json", "results.csv"]


def test_a_swap_killed_midway_after_some_earlier_files_moved_aside_restores_them_all(tmp_path, monkeypatch):
    out = tmp_path / "run"
    _first_run(out, {"a.json": "A", "b.json": "B", "c.json": "C"})
    owner = claim(out, force=True)
    _write(owner.path, {"a.json": "a2", "b.json": "b2", "c.json": "c2"})
    real_replace, moves = os.replace, []

    def dies_at_the_second_move(src, dst):
        if ".somarm-old" in str(dst):
            moves.append(dst)
            if len(moves) == 2:
                raise KeyboardInterrupt  # killed with one earlier file aside and two still in place
        return real_replace(src, dst)

    monkeypatch.setattr(claim_module.os, "replace", dies_at_the_second_move)
    with pytest.raises(KeyboardInterrupt):
        owner.commit()
    monkeypatch.setattr(claim_module.os, "replace", real_replace)
    owner.release()
    claim(out, force=True).release()
    assert _listing(out) == {"a.json": "A", "b.json": "B", "c.json": "C"}


def test_new_results_never_overwrite_a_file_somarm_did_not_write(tmp_path):
    out = tmp_path / "run"
    _first_run(out, {"config.json": "old"})
    _write(out, {"learning_curve.png": "my own picture"})
    owner = claim(out, force=True)
    _write(owner.path, {"config.json": "new", "learning_curve.png": "a figure"})
    with pytest.raises(ValueError, match="learning_curve.png, which somarm did not write there .* they are in"):
        owner.commit()
    owner.release()
    assert _listing(out)["learning_curve.png"] == "my own picture" and _listing(out)["config.json"] == "old"
    kept = next(p for p in out.iterdir() if p.name.startswith("somarm-results-"))
    assert (kept / "learning_curve.png").read_text() == "a figure"


def test_an_incomplete_run_does_not_replace_an_earlier_one_but_stands_where_there_was_none(tmp_path):
    out = tmp_path / "run"
    _first_run(out, {"config.json": "old"})
    owner = claim(out, force=True)
    _write(owner.path, {"config.json": "partial"})
    owner.finish(False)
    owner.release()
    assert _listing(out) == {"config.json": "old"}
    fresh = claim(tmp_path / "fresh")
    _write(fresh.path, {"config.json": "partial"})
    fresh.finish(False)
    fresh.release()
    assert _listing(tmp_path / "fresh") == {"config.json": "partial"}


def test_a_file_added_during_a_run_is_not_listed_as_the_runs(tmp_path):
    out = tmp_path / "run"
    owner = claim(out)
    _write(owner.path, {"config.json": "1"})
    _write(out, {"my.txt": "added while the run went on"})
    owner.commit()
    owner.release()
    assert json.loads((out / MANIFEST_NAME).read_text())["files"] == ["config.json"]


def test_a_refused_folder_is_left_as_it_was_found(tmp_path):
    mine = tmp_path / "mine"
    _write(mine, {"notes.txt": "x"})
    with pytest.raises(ValueError, match="is not empty"):
        claim(mine)
    assert sorted(p.name for p in mine.iterdir()) == ["notes.txt"]
