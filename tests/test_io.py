import json
import os
import stat
from pathlib import Path

import numpy as np
import pytest

from somarm.io import atomic_save_npz, atomic_write_bytes, atomic_write_json, atomic_write_text


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


def test_a_device_or_a_pipe_is_refused_and_left_as_it_is(tmp_path):
    pipe = tmp_path / "pipe"
    os.mkfifo(pipe)
    for path in (pipe, Path("/dev/full"), Path("/dev/null")):
        with pytest.raises(ValueError, match="is not a regular file"):
            atomic_write_bytes(path, b"x")
    assert stat.S_ISFIFO(pipe.stat().st_mode) and stat.S_ISCHR(os.stat("/dev/full").st_mode)


def test_a_link_is_written_through_to_its_file(tmp_path):
    target = tmp_path / "real.html"
    target.write_text("old")
    link = tmp_path / "link.html"
    link.symlink_to(target)
    atomic_write_bytes(link, b"new")
    assert link.is_symlink() and target.read_text() == "new"
