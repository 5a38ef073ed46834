"""The SB3-style ``SOMQ`` model: save and load through a claimed run folder."""

import subprocess
import sys

import numpy as np
import pytest

from somarm import SOMQ

pytest.importorskip("gymnasium")


def _model(steps: int = 200) -> SOMQ:
    model = SOMQ("Pendulum-v1", seed=3)
    model.learn(total_timesteps=steps)
    return model


def test_a_saved_model_loads_with_the_same_greedy_actions_and_replaces_an_earlier_save(tmp_path):
    folder = tmp_path / "model"
    _model(200).save(folder)
    (folder / "notes.txt").write_text("mine")  # a user's file in the folder stays
    model = _model(400)
    assert model.save(folder) == folder
    loaded = SOMQ.load(folder)
    observations = np.random.default_rng(0).uniform(-1.0, 1.0, (16, 3))
    for observation in observations:
        assert np.array_equal(loaded.predict(observation, deterministic=True)[0],
                              model.predict(observation, deterministic=True)[0])
    assert (folder / "notes.txt").read_text() == "mine"
    assert not list(folder.glob(".somarm-new*")) and not list(folder.glob(".somarm-old*"))


def test_saving_into_a_folder_another_process_writes_is_refused_in_one_line(tmp_path):
    folder = tmp_path / "model"
    holder = subprocess.Popen(
        [sys.executable, "-c", "import sys, time; from pathlib import Path; from somarm.run.claim import claim; "
         "held = claim(Path(sys.argv[1])); print('held', flush=True); time.sleep(60)", str(folder)],
        stdout=subprocess.PIPE, text=True)
    try:
        assert holder.stdout.readline().strip() == "held"
        model = _model(200)
        with pytest.raises(ValueError) as caught:
            model.save(folder)
        message = str(caught.value)
        assert "\n" not in message and "being written by another somarm process" in message
        assert f"pid {holder.pid}" in message
    finally:
        holder.kill()
        holder.wait()
    model.save(folder)  # the kernel freed the lock with the process
    assert (folder / "learner.npz").exists()
