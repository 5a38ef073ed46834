import json
import os
import stat
from pathlib import Path

import numpy as np
import pytest

from somarm.io import (
    NON_FINITE,
    atomic_save_npz,
    atomic_write_bytes,
    atomic_write_json,
    atomic_write_text,
    make_folder,
    read_json,
)


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


def test_a_link_is_replaced_by_the_file_and_its_target_left_as_it_was(tmp_path):
    target = tmp_path / "real.html"
    target.write_text("old")
    link = tmp_path / "link.html"
    link.symlink_to(target)
    atomic_write_bytes(link, b"new")
    assert not link.is_symlink() and link.read_text() == "new" and target.read_text() == "old"


def test_a_link_standing_for_a_folder_inside_the_owned_folder_is_refused(tmp_path):
    outside = tmp_path / "outside"
    outside.mkdir()
    owned = tmp_path / "owned"
    owned.mkdir()
    (owned / "seeds").symlink_to(outside)
    with pytest.raises(ValueError, match="seeds is a symbolic link"):
        atomic_write_bytes(owned / "seeds" / "a.json", b"x", within=owned)
    with pytest.raises(ValueError, match="seeds is a symbolic link"):
        make_folder(owned / "seeds" / "deeper", within=owned)
    assert list(outside.iterdir()) == []


def test_json_holds_no_nan_and_reads_back_what_it_flagged(tmp_path):
    path = tmp_path / "a.json"
    atomic_write_json(path, {"a": [1.0, float("nan")], "b": {"c/d": float("-inf")}, "e": np.float32(2.5)})
    text = path.read_text()
    assert "NaN" not in text and "Infinity" not in text
    json.loads(text, parse_constant=lambda name: pytest.fail(name))  # strict JSON
    back = read_json(path)
    assert back["a"][0] == 1.0 and np.isnan(back["a"][1]) and back["b"]["c/d"] == -np.inf and back["e"] == 2.5
    assert NON_FINITE not in back


@pytest.mark.parametrize("content", [b"[" * 100_000, b"NaN", b"\xff\xfe", b"{"])
def test_a_damaged_json_file_is_one_line_naming_it(tmp_path, content):
    path = tmp_path / "d.json"
    path.write_bytes(content)
    with pytest.raises(ValueError, match=str(path)) as caught:
        read_json(path)
    assert "\n" not in str(caught.value)


def test_reading_json_refuses_a_link_and_a_file_too_large_before_reading_it(tmp_path):
    big = tmp_path / "big.json"
    big.write_bytes(b" " * 2000)
    with pytest.raises(ValueError, match="2000 bytes"):
        read_json(big, max_bytes=1000)
    link = tmp_path / "zero.json"
    link.symlink_to("/dev/zero")
    with pytest.raises(ValueError, match="symbolic link"):
        read_json(link)
