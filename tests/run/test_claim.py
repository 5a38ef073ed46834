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
    assert not owner.staged and owner.path == folder
    _write(owner.path, files)
    owner.commit()
    owner.release()


def test_a_first_run_writes_in_place_and_lists_what_it_wrote(tmp_path):
    out = tmp_path / "run"
    _first_run(out, {"config.json": "old", "figures/a.png": "A"})
    assert json.loads((out / MANIFEST_NAME).read_text())["files"] == ["config.json", "figures/a.png"]


def test_a_forced_run_replaces_only_what_the_earlier_run_wrote(tmp_path):
    out = tmp_path / "run"
    _first_run(out, {"config.json": "old", "old.png": "O", "figures/a.png": "A"})
    _write(out, {"photo.png": "mine", "figures/notes.txt": "mine too"})
    owner = claim(out, force=True)
    assert owner.staged and owner.path != out
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
