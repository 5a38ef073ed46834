"""Any MuJoCo model in the viewer: a Gymnasium environment's states drawn at MuJoCo's poses, without a browser."""

from __future__ import annotations

import json

import mujoco
import numpy as np
import pytest
import umsgpack

from somarm.viewer.client import Recorder
from somarm.viewer.model_view import ModelShow, Rollout, record_states, rollout, view_states

gymnasium = pytest.importorskip("gymnasium", reason="gymnasium (the peers extra) is not installed")


@pytest.fixture(scope="module")
def pendulum():
    env = gymnasium.make("InvertedPendulum-v5")
    yield env
    env.close()


def body_position(model: mujoco.MjModel, qpos: np.ndarray, body: int) -> np.ndarray:
    data = mujoco.MjData(model)
    data.qpos[:] = qpos
    mujoco.mj_kinematics(model, data)
    return data.xpos[body].copy()


def test_a_rollout_is_seeded_and_keeps_every_state(pendulum):
    first = rollout(pendulum, n_steps=30, seed=4)
    again = rollout(pendulum, n_steps=30, seed=4)
    other = rollout(pendulum, n_steps=30, seed=5)
    assert first.qpos.shape == (31, pendulum.unwrapped.model.nq) and first.rewards.shape == (30,)
    np.testing.assert_array_equal(first.qpos, again.qpos)
    assert not np.array_equal(first.qpos, other.qpos)
    assert first.timestep == pytest.approx(pendulum.unwrapped.dt)
    held = rollout(pendulum, lambda observation: np.zeros(1), n_steps=400, seed=0, until_done=True)
    assert len(held.qpos) - 1 == len(held.rewards) < 400 and held.resets == []  # it falls, and the rollout ends
    lines = held.describe(len(held.qpos) - 1)
    assert lines[0].startswith(f"episode 1: step {len(held.rewards)}") and "return so far" in lines[1]
    with pytest.raises(ValueError, match="model and data"):
        rollout(object())


def test_the_animation_holds_each_body_at_mujocos_pose(pendulum):
    states = rollout(pendulum, n_steps=40, seed=1)
    model = pendulum.unwrapped.model
    recorder = Recorder()
    show = record_states(model, states.qpos, recorder, timestep=states.timestep, title="InvertedPendulum-v5",
                         describe=states.describe)
    animation = recorder.commands()[-1]
    assert animation["type"] == "set_animation"
    fps = animation["animations"][0]["clip"]["fps"]
    assert fps == pytest.approx(1.0 / states.timestep)  # 25 states a second: real time, none skipped
    pole = model.body("pole").id
    clip = next(a for a in animation["animations"] if a["path"] == "/meshcat/model/pole")
    keys = next(t for t in clip["clip"]["tracks"] if t["name"] == ".position")["keys"]
    for k in (0, 17, 40):
        np.testing.assert_allclose(keys[k]["value"], body_position(model, states.qpos[k], pole), atol=1e-9)
    assert {"cart", "pole"} <= set(show.scene.body_names)
    assert recorder.text["title"] == "InvertedPendulum-v5"
    assert recorder.text["timeline"]["frames"][3][1][0].startswith("episode 1: step 3")


def test_mjdata_states_draw_as_their_qpos(pendulum):
    model = pendulum.unwrapped.model
    show = ModelShow(model)
    data = mujoco.MjData(model)
    datas = []
    for k in range(3):
        data.qpos[:] = [0.1 * k, -0.2 * k]
        datas.append(mujoco.MjData(model))
        datas[-1].qpos[:] = data.qpos
    for d in datas:
        assert show.frame(d) == show.frame(d.qpos.copy())
    low, high = show.box(datas)
    assert np.all(high > low)


def test_view_states_writes_a_page_and_refuses_no_states(pendulum, tmp_path):
    states = rollout(pendulum, n_steps=10, seed=0)
    path = view_states(pendulum.unwrapped.model, states.qpos, timestep=states.timestep, title="pendulum",
                       describe=states.describe, html=tmp_path / "p.html")
    text = path.read_text()
    assert "<title>pendulum</title>" in text and "SomarmOverlay" in text
    with pytest.raises(ValueError, match="states is empty"):
        record_states(pendulum.unwrapped.model, [], Recorder(), timestep=0.1, title="x")
    assert Rollout(states.qpos, states.rewards, [4], states.timestep).describe(6)[0].startswith("episode 2: step 2")


def test_somarm_view_draws_a_gym_mujoco_run_and_refuses_a_gym_task_without_a_model(tmp_path, capsys):
    from somarm import run
    from somarm.run import RunConfig
    from somarm.viewer.cli import main

    result = run.train(RunConfig(task="gym:Reacher-v5", n_trials=2, n_steps=200, block=100, seed=3), progress=False)
    run.write(result, tmp_path / "run", figures=False)
    page = tmp_path / "reacher.html"
    assert main(["gym:Reacher-v5", "--run", str(tmp_path / "run"), "--goals", "2", "--trial", "1",
                 "--html", str(page)]) == 0
    import base64
    import re

    encoded = json.loads(re.search(r"var commands = (\[.*?\]);", page.read_text()).group(1))
    sent = repr([umsgpack.unpackb(base64.b64decode(e)) for e in encoded])
    assert "<title>gym:Reacher-v5</title>" in page.read_text()
    assert "trial 1" in sent and "fingertip" in sent and "episode 2" in sent
    assert main(["gym:Pendulum-v1", "--html", str(tmp_path / "p.html")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "gym:Pendulum-v1 is not a MuJoCo environment" in err
    assert main(["gym:Reacher-v5", "--run", str(tmp_path / "run"), "--trial", "5", "--html", str(page)]) == 2
    assert "--trial 5 is not a trial of" in capsys.readouterr().err
