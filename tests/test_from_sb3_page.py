"""The "From Stable-Baselines3" page runs: its set-up, then every line of its table, in order."""

import re
from pathlib import Path

import pytest

pytest.importorskip("stable_baselines3")

PAGE = Path(__file__).resolve().parents[1] / "docs" / "from-sb3.md"


def _setup_and_rows() -> tuple[str, list[tuple[str, str]]]:
    text = PAGE.read_text()
    setup = re.search(r"```python\n(.*?)```", text, re.S).group(1)
    rows = []
    for line in text.splitlines():
        cells = [cell.strip() for cell in line.strip().strip("|").split("|")]
        if line.startswith("| ") and len(cells) == 3 and cells[1].startswith("`"):
            rows.append((cells[0], cells[1][1:cells[1].index("`", 1)]))
    return setup, rows


def test_the_page_has_a_line_for_each_of_sb3s_verbs():
    code = " ".join(line for _, line in _setup_and_rows()[1])
    for verb in ("learn(", "callback=", "progress_bar=", "reset_num_timesteps=", "predict(", "episode_start=",
                 "evaluate_policy(", "save(", "SOMQ.load(", "get_env(", "set_env(", "Monitor(", "MlpPolicy", "verbose="):
        assert verb in code, verb


def test_every_line_of_the_table_runs_as_the_page_says(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    setup, rows = _setup_and_rows()
    namespace: dict = {}
    exec(setup, namespace)
    for what, line in rows:
        try:
            if line.endswith("# ValueError"):
                with pytest.raises(ValueError):
                    exec(line, namespace)
            else:
                exec(line, namespace)
        except Exception as exc:
            raise AssertionError(f"the line for {what!r} fails: {line}") from exc
    assert (tmp_path / "runs" / "pendulum" / "learner.npz").is_file()
    assert (tmp_path / "pendulum.zip").is_file()  # SB3's one file beside the run folder
