import json

import numpy as np
import pytest

from somarm.io import atomic_save_npz, atomic_write_json, atomic_write_text


def test_atomic_writes_round_trip(tmp_path):
    atomic_write_json(tmp_path / "a.json", {"seed": 3})
    assert json.loads((tmp_path / "a.json").read_text()) == {"seed": 3}
    atomic_save_npz(tmp_path / "b.npz", x=np.arange(3))
    np.testing.assert_array_equal(np.load(tmp_path / "b.npz")["x"], np.arange(3))
    assert [p.name for p in tmp_path.iterdir() if p.suffix == ".tmp"] == []


def test_missing_folder_is_one_clear_error(tmp_path):
    with pytest.raises(ValueError, match="does not exist"):
        atomic_write_text(tmp_path / "nope" / "c.txt", "x")


def test_interrupted_write_keeps_old_file(tmp_path, monkeypatch):
    target = tmp_path / "d.txt"
    atomic_write_text(target, "old")

    def boom(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr("os.replace", boom)
    with pytest.raises(KeyboardInterrupt):
        atomic_write_text(target, "new")
    assert target.read_text() == "old"
    assert list(tmp_path.iterdir()) == [target]


def test_written_files_get_the_usual_mode(tmp_path):
    import os

    old = os.umask(0o022)
    try:
        atomic_write_text(tmp_path / "e.txt", "x")
    finally:
        os.umask(old)
    assert (tmp_path / "e.txt").stat().st_mode & 0o777 == 0o644
