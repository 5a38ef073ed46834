"""What the task shows draw and say, checked against MuJoCo and the tasks, without a browser."""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

from somarm.tasks.throw import simulate_trajectory
from somarm.viewer import overlays, shows
from somarm.viewer.client import Recorder
from somarm.viewer.feed import own_task
from somarm.viewer.postures import SweepShow
from somarm.viewer.shows import ArmShow, arm_animation, load_model
from somarm.viewer.task_shows import show_for_task
from somarm.viewer.text import Timeline, css, number, text_command
from somarm.viewer.throws import ThrowShow, ball_color


def sent(commands: list[dict], kind: str = "set_transform") -> dict[str, dict]:
    """The last command of a kind for each path."""
    return {c["path"]: c for c in commands if c["type"] == kind}


def matrix(command: dict) -> np.ndarray:
    return np.array(command["matrix"]).reshape(4, 4).T


def positions(command: dict) -> np.ndarray:
    """The vertices ``(n, 3)`` of a buffer geometry's set_object (meshcat packs them as float32 bytes)."""
    packed = command["object"]["geometries"][0]["data"]["attributes"]["position"]["array"]
    return np.frombuffer(packed.data, dtype=np.float32).reshape(-1, 3)


def color_of(command: dict) -> int:
    return command["object"]["materials"][0]["color"]


def two_link_angles(tip) -> np.ndarray:
    """Joint angles putting arm2's fingertip (links 0.4, base (0.5, 0)) at ``tip`` (elbow one way)."""
    x, y = tip[0] - 0.5, tip[1]
    cos2 = (x * x + y * y - 0.32) / 0.32
    theta2 = math.acos(max(-1.0, min(1.0, cos2)))
    theta1 = math.atan2(y, x) - math.atan2(0.4 * math.sin(theta2), 0.4 + 0.4 * math.cos(theta2))
    return np.array([theta1, theta2])


def test_arm_show_error_is_the_tasks_reward_and_the_tip_is_mujocos_site():
    rng = np.random.default_rng(5)
    for name in ("reach2", "four_goals", "reach20"):
        task = own_task(name, None)
        show = show_for_task(name, task)
        observations = task.sample_observations(rng, 4)
        actions = rng.uniform(task.action_low, task.action_high, (4, task.action_low.size))
        rewards = task.evaluate(observations, actions)
        for observation, action, reward in zip(observations, actions, rewards, strict=True):
            commands = show.frame(observation, action, reward)
            assert np.isclose(show.last_error, -reward, atol=1e-9), name
            tip = matrix(sent(commands)[show.prefix.append("fingertip").lower()])[:3, 3]
            data = mujoco.MjData(show.model)
            data.qpos[:] = action
            mujoco.mj_forward(show.model, data)
            site = mujoco.mj_name2id(show.model, mujoco.mjtObj.mjOBJ_SITE, "fingertip")
            np.testing.assert_allclose(tip[:2], data.site_xpos[site][:2], atol=1e-9)
            assert tip[2] > 0  # drawn just above the arm, so the link's end never hides it


def test_the_goal_ring_is_above_and_larger_than_the_fingertip():
    show = ArmShow(load_model("arm2"), prefix="/meshcat/a")
    setup = sent(show.setup(), "set_object")
    assert "/meshcat/a/link1/link1/cylinder" in setup and not any("/goal/" in p for p in setup)  # the model's ball
    tip_radius = setup["/meshcat/a/fingertip"]["object"]["geometries"][0]["radius"]
    ring_radius = np.linalg.norm(positions(setup["/meshcat/a/goal"])[:, :2], axis=1).max()
    assert ring_radius > 2 * tip_radius
    assert color_of(setup["/meshcat/a/goal"]) == shows.GOAL_COLOR != color_of(setup["/meshcat/a/fingertip"])
    frame = sent(show.frame(np.array([0.5, 0.6]), np.array([1.2, 0.7])))
    goal, tip = matrix(frame["/meshcat/a/goal"])[:3, 3], matrix(frame["/meshcat/a/fingertip"])[:3, 3]
    np.testing.assert_allclose(goal[:2], [0.5, 0.6])
    assert goal[2] > tip[2] + tip_radius  # above the fingertip ball: a reached goal rings the tip


def test_an_error_through_the_wall_is_drawn_faint_and_said_so():
    task = own_task("reach2_obstacle", None)
    show = show_for_task("reach2_obstacle", task)
    goal = np.array([0.32, 0.62])  # a goal behind the wall; the observation holds the angles and the goal
    for tip, through in (((0.72, 0.62), "wall"), ((0.30, 0.45), None)):
        angles = np.concatenate([two_link_angles(tip), goal])
        commands = sent(show.frame(angles, np.zeros(2)))
        assert show.last_crossing == through
        solid, faint = matrix(commands[show.prefix.append("error").lower()]), \
            matrix(commands[show.prefix.append("error_through").lower()])
        shown = faint if through else solid
        np.testing.assert_allclose(np.linalg.norm(shown[:3, 1]), np.linalg.norm(np.subtract(tip, goal)), atol=1e-6)
        assert np.abs((solid if through else faint)[:3, :3]).max() < 1e-6  # the other one is hidden
        caption = " ".join(show.caption(0, 1, angles))
        assert ("through the wall" in caption) == bool(through)


def test_the_top_view_looks_down_on_the_whole_table_with_a_grid_and_a_scale():
    show = ArmShow(load_model("arm2"), prefix="/meshcat/a")
    commands = show.setup()
    camera = sent(commands, "set_property")
    position = next(c["value"] for c in commands if c["type"] == "set_property" and c["property"] == "position")
    x, z, minus_y = position  # three.js y-up: (x, z, -y)
    assert z > 20 * max(abs(x), abs(minus_y))  # straight down, to within a degree
    shift = -matrix(sent(commands)["/meshcat"])[:3, 3]
    fov = next(c["value"] for c in commands if c["type"] == "set_property" and c["property"] == "fov")
    half_height = math.tan(math.radians(fov) / 2) * (z + 0.02)
    for corner in ((0, 0), (1, 1), (0, 1), (1, 0)):  # the unit square's corners lie inside the frame
        assert abs(corner[1] - shift[1]) < half_height
        assert abs(corner[0] - shift[0]) < overlays.ASPECT * half_height
    assert camera  # properties were sent
    grid = sent(commands, "set_object")["/meshcat/a/grid"]
    points = positions(grid).astype(np.float64)
    vertical = points[0::2][points[0::2, 0] == points[1::2, 0]]  # segments of constant x
    np.testing.assert_allclose(vertical[:, 0] / 0.2, np.round(vertical[:, 0] / 0.2), atol=1e-5)  # on multiples
    assert points[:, 0].min() <= 0.0 and points[:, 0].max() >= 1.0 and points[:, 1].max() >= 1.0
    assert show.view_text["labels"][0][1] == "0.2" and ["#aeb6c4", "grid 0.2"] in show.key()


def test_a_sweep_has_one_goal_and_error_colour_and_shaded_postures():
    model = load_model("arm20")
    sweep = SweepShow(model, 3, prefix="/meshcat/s")
    objects = sent(sweep.setup(), "set_object")
    goals = {color_of(c) for p, c in objects.items() if p.endswith("/goal")}
    errors = {color_of(c) for p, c in objects.items() if p.endswith("/error")}
    assert goals == {shows.GOAL_COLOR} and errors == {shows.ERROR_COLOR}
    links = [color_of(objects[f"/meshcat/s/posture{k:02d}/link5/link5/cylinder"]) for k in range(3)]
    assert links == [shows.shade(0.0), shows.shade(0.5), shows.shade(1.0)] and len(set(links)) == 3
    assert sum(p.endswith("/unit_square/shape") for p in objects) == 1  # the table once
    angles = np.zeros((3, 20))
    goals_xy = np.array([[0.4, 0.5], [0.5, 0.6], [0.6, 0.5]])
    sweep.frame(goals_xy, angles)
    text = sweep.text(type("S", (), {"title": lambda self: "t", "lines": lambda self: []})())
    assert "mean error" in text["caption"][0] and [css(shows.shade(0.0)), "posture of goal 1"] in text["key"]


def test_arm_animation_text_follows_the_goals():
    show = ArmShow(load_model("arm2"), prefix="/meshcat/a")
    goals, actions = np.array([[0.4, 0.5], [0.7, 0.6]]), np.array([[1.2, 0.8], [0.3, 1.5]])
    animation, timeline = arm_animation(show, goals, actions)
    first, second = timeline.at(0), timeline.at(24 + 12 + 1)
    assert first[0] == "goal 1 of 2 at (0.400, 0.500)" and second[0].startswith("goal 2 of 2")
    show.frame(goals[1], actions[1])
    assert second[1] == f"error {number(show.last_error)}"
    assert timeline.at(30)[0] == "moving to goal 2 of 2"
    clips = {a["path"] for a in animation["animations"]}
    assert "/meshcat/a/link2" in clips and "/meshcat/a/goal" in clips


def test_throw_trails_take_their_balls_colour_and_each_landing_is_marked():
    model = load_model("launcher")
    fan = np.array([[0.35, 0.2], [0.3, 0.5], [0.2, 0.8]])
    show = ThrowShow(model, simulate_trajectory, n_balls=3, prefix="/meshcat/t")
    commands = show.setup() + show.throw_commands(fan, 4.0)
    objects = sent(commands, "set_object")
    assert not any("projectile" in p for p in objects)  # the balls are the projectiles
    for k in range(3):
        color = ball_color(k, 3)
        assert color_of(objects[f"/meshcat/t/ball{k:02d}"]) == color
        assert color_of(objects[f"/meshcat/t/trail{k:02d}"]) == color
        assert color_of(objects[f"/meshcat/t/landing{k:02d}"]) == color
    assert len({ball_color(k, 3) for k in range(3)}) == 3
    animation = commands[-1]
    for k, (ux, uy) in enumerate(fan):
        landing_x = simulate_trajectory(ux, uy)[1][-1, 0]
        clip = next(a for a in animation["animations"] if a["path"] == f"/meshcat/t/landing{k:02d}")
        scale = next(t for t in clip["clip"]["tracks"] if t["name"] == ".scale")["keys"]
        position = next(t for t in clip["clip"]["tracks"] if t["name"] == ".position")["keys"]
        assert scale[0]["value"][0] < 1e-6 and scale[-1]["value"][0] == pytest.approx(1.0)  # appears on landing
        assert position[-1]["value"][0] == pytest.approx(landing_x, abs=1e-9)
        ball = next(a for a in animation["animations"] if a["path"] == f"/meshcat/t/ball{k:02d}")
        last = next(t for t in ball["clip"]["tracks"] if t["name"] == ".position")["keys"][-1]["value"]
        assert last[0] == pytest.approx(landing_x, abs=1e-9) and abs(last[2]) < 1e-9
    ticks = dict((label, path) for path, label in show.view_text["labels"])
    assert {"0", "1", "2", "3", "4"} <= set(ticks) or {"0", "0.5", "4"} <= set(ticks)


def test_a_sequence_of_throws_shows_each_trail_only_while_it_flies():
    task = own_task("throw_distance", None)
    stream = show_for_task("throw_distance", task)
    observations = task.sample_observations(np.random.default_rng(0), 3)
    actions = np.array([[0.3, 0.5], [0.4, 0.6], [0.2, 0.7]])
    commands, timeline = stream.show.sequence_commands(
        actions, [stream.target_of(o) for o in observations], [stream.trajectory_of(o) for o in observations],
        [stream.caption(k, 3, o, a) for k, (o, a) in enumerate(zip(observations, actions, strict=True))])
    animation = commands[-1]
    starts = [start for start, _ in timeline.frames]
    assert len(starts) == 3 and timeline.frames[1][1][0].startswith("throw 2 of 3: target x =")

    def scale_at(path: str, frame: int) -> float:
        clip = next(a for a in animation["animations"] if a["path"] == path)
        keys = next(t for t in clip["clip"]["tracks"] if t["name"] == ".scale")["keys"]
        return float(np.interp(frame, [k["time"] for k in keys], [k["value"][0] for k in keys]))

    for j in range(3):
        trail = f"{stream.show.prefix.lower()}/trail{j:02d}"
        for k, start in enumerate(starts):
            assert (scale_at(trail, start + 2) > 0.5) == (j == k)
    landed, miss = stream.landing_miss(observations[0], actions[0])
    assert miss == pytest.approx(abs(landed - stream.target_of(observations[0])))
    assert f"miss {number(miss)}" in timeline.frames[0][1][1]


def test_text_commands_and_the_recorder_merge_fields():
    with pytest.raises(ValueError, match="unknown overlay field.*fields: title"):
        text_command(colour="red")
    recorder = Recorder()
    recorder.send(text_command(title="reach2", lines=["a"], key=[["#ff0000", "goal"]]))
    recorder.send(text_command(status="training finished"))
    (merged,) = [c for c in recorder.commands() if c["type"] == "somarm_text"]
    assert merged["title"] == "reach2" and merged["status"] == "training finished" and merged["lines"] == ["a"]
    timeline = Timeline(30)
    timeline.add(10, ["one"])
    timeline.add(5, ["one"])
    timeline.add(3, ["two"])
    assert timeline.frames == [[0, ["one"]], [15, ["two"]]] and timeline.n_frames == 18
    assert timeline.at(14) == ["one"] and timeline.at(15) == ["two"]
    assert number(0.01234) == "0.012" and number(-1.5) == "-1.500" and number(2e-5) == "2.0e-05"
    assert css(0x1E9E4A) == "#1e9e4a"


def test_nice_steps_and_a_fitted_camera_hold_the_box():
    assert overlays.nice_step(1.0, n_lines=8) == pytest.approx(0.2)
    assert overlays.nice_step(30.0, n_lines=10) == pytest.approx(5.0)
    low, high = np.array([-1.0, -0.5, 0.0]), np.array([3.0, 0.5, 2.0])
    commands = overlays.fit_camera(low, high, [0.0, -1.0, 0.2], margin=0.0)
    centre = -matrix(sent(commands)["/meshcat"])[:3, 3]
    x, z, minus_y = next(c["value"] for c in commands if c.get("property") == "position")
    camera = np.array([x, -minus_y, z])
    forward = -camera / np.linalg.norm(camera)
    right = np.cross(forward, [0.0, 0.0, 1.0])
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    tan_v = math.tan(math.radians(overlays.FOV_DEGREES) / 2)
    worst = 0.0
    for corner in np.array(np.meshgrid(*zip(low, high, strict=True))).T.reshape(-1, 3):
        relative = corner - centre - camera
        depth = relative @ forward
        worst = max(worst, abs(relative @ up) / (depth * tan_v), abs(relative @ right) / (depth * tan_v * overlays.ASPECT))
    assert 0.97 < worst <= 1.0 + 1e-9  # every corner inside the frame, and the frame no larger than needed
