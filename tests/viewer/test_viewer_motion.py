"""The viewer animates driven arms along their MuJoCo trajectories: every frame is MuJoCo's pose."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from somarm.tasks import obstacle
from somarm.viewer import sessions
from somarm.viewer.client import Recorder


def _body_position(model: mujoco.MjModel, qpos: np.ndarray, body: str) -> np.ndarray:
    data = mujoco.MjData(model)
    data.qpos[:] = qpos
    mujoco.mj_forward(model, data)
    return data.xpos[model.body(body).id].copy()


def _track(animation: dict, suffix: str, kind: str) -> list[dict]:
    clip = next(a for a in animation["animations"] if a["path"].endswith(suffix))
    return next(t for t in clip["clip"]["tracks"] if t["name"] == f".{kind}")["keys"]


@pytest.mark.parametrize("task_name, task_set", [("reach2", {"dynamics": "actuated"}), ("reach2_obstacle", {})])
def test_every_animation_frame_holds_the_arm_at_mujocos_pose_along_the_path(task_name, task_set):
    session = sessions.load_session(task_name, n_goals=2, seed=1, task_set=task_set)
    assert session.paths is not None and len(session.paths) == 2
    recorder = Recorder()
    sessions.record(session, recorder)
    animation = recorder.commands()[-1]
    assert animation["type"] == "set_animation" and animation["options"]["play"]
    positions = _track(animation, f"/{task_name}/link2", "position")
    model = session.show.model
    frames = [np.asarray(path[::2]) for path in session.paths]
    # Frame k of the first path is the arm at timestep 2k of MuJoCo's trajectory.
    for k in (0, 5, len(frames[0]) - 1):
        expected = _body_position(model, frames[0][k], "link2")
        # A pose that stays (an arm held against the wall) may keep its key: the key in force at frame k.
        key = max((p for p in positions if p["time"] <= k), key=lambda p: p["time"])
        np.testing.assert_allclose(key["value"], expected, atol=1e-9)
    # The paths move: the arm is driven, not set.
    assert np.abs(session.paths[0][-1] - session.paths[0][0]).max() > 0.1


def test_actuated_reach_paths_start_at_rest_and_end_where_the_error_is_measured():
    session = sessions.load_session("reach2", n_goals=3, seed=2, task_set={"dynamics": "actuated",
                                                                         "settle_time": 0.5})
    for path, goal, error in zip(session.paths, session.observations, session.errors, strict=True):
        assert path.shape == (51, 2)
        np.testing.assert_array_equal(path[0], 0.0)
        tip = obstacle.fingertips(path[-1])
        assert np.linalg.norm(tip - goal) == pytest.approx(error, abs=1e-12)


def test_obstacle_episodes_end_at_the_goal_or_the_step_limit_and_draw_wall_and_goal():
    session = sessions.load_session("reach2_obstacle", n_goals=2, seed=0)
    task_limit = obstacle.ObstacleParams().step_limit
    for path, error in zip(session.paths, session.errors, strict=True):
        steps = (len(path) - 1) // 30
        assert error < obstacle.ObstacleParams().tolerance or steps == task_limit
    recorder = Recorder()
    sessions.record(session, recorder)
    drawn = {c["path"] for c in recorder.commands() if c["type"] == "set_object"}
    assert any(p.endswith("/wall/shape") or "/wall" in p for p in drawn)
    assert any("/goal" in p for p in drawn)


def test_an_episode_traces_the_fingertip_and_says_step_return_and_success():
    from somarm.viewer.motion import TRACE_COLOR

    session = sessions.load_session("reach2_obstacle", n_goals=2, seed=0)
    recorder = Recorder()
    sessions.record(session, recorder)
    commands = recorder.commands()
    pieces = [c for c in commands if c["type"] == "set_object" and "/trace/path00/" in c["path"]]
    assert 5 <= len(pieces) <= 40 and all(c["object"]["materials"][0]["color"] == TRACE_COLOR for c in pieces)
    animation = commands[-1]
    last_piece = pieces[-1]["path"]
    scale = _track(animation, last_piece, "scale")
    assert scale[0]["value"][0] < 1e-6  # the end of the path is not drawn before the tip gets there
    assert any(key["value"][0] == 1.0 for key in scale)
    text = recorder.text
    steps = [lines[0] for _, lines in text["timeline"]["frames"] if lines[0].startswith("episode 1 of 2")]
    assert steps[0].startswith("episode 1 of 2: step 0 of") and len(set(steps)) > 2  # the step counts up
    final = text["timeline"]["frames"][len(steps) - 1][1][1]
    assert final.startswith("return so far") and ("goal reached" in final or "step limit" in final)


def test_the_arm_moves_between_goals_the_shorter_way_round():
    from somarm.viewer.shows import joint_path

    start, end = np.array([3.0, -0.5]), np.array([-3.0, 0.5])  # 0.28 rad apart across +-pi for joint 1
    middle = joint_path(start, end, 0.5)
    np.testing.assert_allclose(np.cos(middle[0]), -1.0, atol=1e-12)  # through pi, not through 0
    np.testing.assert_allclose(middle[1], 0.0, atol=1e-12)
    np.testing.assert_allclose(joint_path(start, end, 0.0), start)
    np.testing.assert_allclose(np.exp(1j * joint_path(start, end, 1.0)), np.exp(1j * end), atol=1e-12)
