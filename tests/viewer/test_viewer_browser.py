"""End to end in a real headless Chromium: the page's scene holds the model at MuJoCo's poses.

Needs Debian's ``chromium`` (``.ci/run`` installs it) and Playwright for Python; it never runs
``playwright install``. Where either is missing the tests are skipped with the reason (with CI=true
that skip is a failure, see conftest.py). One browser serves the whole module. Screenshots go to the
test's tmp folder (the docs' pictures come from ``python -m somarm.viewer.snapshot``).
"""

from __future__ import annotations

import io
import os
import time
from pathlib import Path

import mujoco
import numpy as np
import pytest
from meshcat.commands import Delete, SetProperty

from somarm.tasks.throw import simulate_trajectory
from somarm.viewer.client import MeshcatClient, Recorder
from somarm.viewer.html import write_html
from somarm.viewer.postures import SweepShow
from somarm.viewer.scene import path_of
from somarm.viewer.server import MeshcatServer
from somarm.viewer.shows import ArmShow, load_model
from somarm.viewer.text import number
from somarm.viewer.throws import ThrowShow

CHROMIUM = "/usr/bin/chromium"
ARGS = [
    "--no-sandbox", "--headless=new", "--enable-unsafe-swiftshader", "--use-gl=angle", "--use-angle=swiftshader",
    "--disable-background-networking", "--disable-component-update", "--disable-sync", "--no-first-run",
    "--disable-default-apps", "--disable-extensions",
]
TIMEOUT_MS = 30_000

pytestmark = [
    pytest.mark.browser,
    pytest.mark.skipif(not os.path.exists(CHROMIUM), reason=f"Debian's chromium is not installed at {CHROMIUM}"),
]
sync_api = pytest.importorskip("playwright.sync_api", reason="Playwright for Python is not installed")

# Relative pose of a named node to the show's root: what the page draws, in MuJoCo's frame.
RELATIVE_POSE = """([root, names]) => {
  const base = viewer.scene_tree.find(root).object;
  viewer.scene.updateMatrixWorld(true);
  const inverse = base.matrixWorld.clone().invert();
  const out = {};
  for (const name of names) {
    const node = viewer.scene_tree.find(root.concat(name.split('/'))).object;
    out[name] = Array.from(inverse.clone().multiply(node.matrixWorld).elements);
  }
  return out;
}"""


@pytest.fixture(scope="module")
def browser():
    with sync_api.sync_playwright() as playwright:
        chromium = playwright.chromium.launch(executable_path=CHROMIUM, args=ARGS, timeout=TIMEOUT_MS)
        yield chromium
        chromium.close()


@pytest.fixture
def server():
    running = MeshcatServer().start()
    yield running
    running.stop()


def open_page(browser, url: str):
    page = browser.new_page(viewport={"width": 900, "height": 640})
    page.set_default_timeout(TIMEOUT_MS)
    # Loopback only: any request to another host fails the test instead of leaving the machine.
    foreign = []

    def guard(route):
        if route.request.url.startswith(("http://127.0.0.1", "ws://127.0.0.1", "data:", "blob:", "file://")):
            route.continue_()
        else:
            foreign.append(route.request.url)
            route.abort()

    page.route("**/*", guard)
    page.goto(url)
    page.foreign_requests = foreign
    return page


def screenshot(page, tmp_path: Path, name: str) -> np.ndarray:
    """Save a PNG; return its pixels ``(h, w, 3)``."""
    from PIL import Image

    png = page.screenshot()
    (tmp_path / name).write_bytes(png)
    return np.asarray(Image.open(io.BytesIO(png)).convert("RGB"), dtype=np.int16)


def overlay(page) -> str:
    """The text the page's overlay panel shows."""
    return page.inner_text("#somarm-panel")


def settle(page) -> None:
    page.wait_for_function("() => typeof viewer !== 'undefined' && viewer.renderer !== undefined")
    page.evaluate("() => new Promise(done => requestAnimationFrame(() => requestAnimationFrame(done)))")


def mujoco_pose(model: mujoco.MjModel, qpos: np.ndarray, mocap_pos: np.ndarray | None, geom: str) -> np.ndarray:
    data = mujoco.MjData(model)
    data.qpos[:] = qpos
    if mocap_pos is not None:
        data.mocap_pos[:] = mocap_pos
    mujoco.mj_forward(model, data)
    gid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, geom)
    pose = np.eye(4)
    pose[:3, :3] = data.geom_xmat[gid].reshape(3, 3)
    pose[:3, 3] = data.geom_xpos[gid]
    return pose


def drawn_pose(page, root: list[str], node: str) -> np.ndarray:
    """The pose the page draws a node at, relative to ``root`` (three.js matrices are column-major)."""
    return np.array(page.evaluate(RELATIVE_POSE, [root, [node]])[node]).reshape(4, 4).T


def test_the_page_holds_the_arm_at_mujocos_poses(browser, server, tmp_path):
    model = load_model("arm2")
    show = ArmShow(model, prefix="/meshcat/reach2")
    goal, action = np.array([0.62, 0.55]), np.array([0.9, 1.3])
    client = MeshcatClient(server.zmq_url, timeout_s=10)
    assert client.send_batch(show.setup()) and client.send_batch(show.frame(goal, action))
    page = open_page(browser, server.web_url)
    geoms = {"link1/link1": "link1", "link2/link2": "link2", "world/base": "base",
             "link1/link1/cylinder": "link1", "link2/link2/cap1": "link2"}
    page.wait_for_function("() => typeof viewer !== 'undefined' && "
                           "viewer.scene.getObjectByName('link2') !== undefined")
    settle(page)
    drawn = page.evaluate(RELATIVE_POSE, [["meshcat", "reach2"], list(geoms)])
    for name, geom in geoms.items():
        got = np.array(drawn[name]).reshape(4, 4).T  # three.js matrices are column-major
        expected = mujoco_pose(model, action, np.array([[*goal, 0.0]]), geom)
        if name.count("/") == 2:
            part = name.rsplit("/", 1)[1]
            expected = expected @ {p.name: p.local for p in show.scene.parts[
                show.scene.geom_ids[show.scene.names.index(geom)]]}[part]
        np.testing.assert_allclose(got, expected, atol=1e-5, err_msg=name)  # float32 in the browser
    np.testing.assert_allclose(drawn_pose(page, ["meshcat", "reach2"], "goal")[:2, 3], goal, atol=1e-6)
    assert page.evaluate("() => viewer.renderer.getContext() !== null")
    assert page.title() == "somarm" and overlay(page) == ""  # nothing said yet: this page was sent no text

    pixels = screenshot(page, tmp_path, "viewer-reach2.png")
    client.send(SetProperty("visible", False, path_of("/meshcat/reach2")).lower())
    settle(page)
    hidden = screenshot(page, tmp_path, "hidden.png")
    changed = np.abs(pixels - hidden).sum(axis=2) > 30
    assert pixels.std() > 10, "the screenshot is blank"
    assert changed.mean() > 0.01, "hiding the arm changed almost nothing: it was not drawn"
    assert page.foreign_requests == []
    page.close()
    client.close()


def test_live_training_is_followed_counted_and_said_finished(browser, tmp_path):
    from somarm import run
    from somarm.viewer.live import LiveView, greedy_policy

    config = run.RunConfig(task="reach2", n_steps=4000, seed=3)
    group = run.RunGroup([config])
    with LiveView("reach2", policy=greedy_policy(group.learners[0]), hold_s=0.3, n_goals=4, n_steps=4000,
                  lines=["somq learner, trial 0, seed 3"]) as view:
        bare = view.url.replace("/static/", "/")
        page = open_page(browser, bare)  # the bare address leads to the viewer
        assert page.url == view.url and page.title() == "reach2"
        page.wait_for_function("() => document.getElementById('somarm-panel').innerText.includes('waiting')")
        seen = []

        def watch(step, observations, actions, rewards):
            view.update(step, observations, actions, rewards)
            if step in (500, 3000):  # look at the page twice while training runs
                # Training may outrun the hold (2,500 reach2 steps can take less than 0.3 s): offer this
                # step again once a hold has passed, so the page is sent it whatever the machine's speed.
                time.sleep(view.hold_s + 0.05)
                view.update(step, observations, actions, rewards)
                page.wait_for_function(f"() => /training: step [0-9,]+ of 4,000/.test("
                                       f"document.getElementById('somarm-panel').innerText) && "
                                       f"!document.getElementById('somarm-panel').innerText.includes("
                                       f"'step {seen[-1] if seen else 'none'} of')")
                text = overlay(page)
                seen.append(text.split("training: step ")[1].split(" of")[0])
                assert "reach2: greedy pose, a cycle of 4" in text and "running mean reward" in text

        result = group.train(progress=False, on_step=watch)[0]
        assert len(set(seen)) == 2 and int(seen[1].replace(",", "")) > int(seen[0].replace(",", ""))
        view.finish(result.steps_done)
        page.wait_for_function("() => document.getElementById('somarm-panel').innerText.includes("
                               "'training finished after 4,000 steps')")
        goals = set()
        for _ in range(30):  # after training the server keeps showing the final policy, goal after goal
            goals |= {line for line in overlay(page).splitlines() if line.startswith("goal ")}
            if len(goals) >= 2:
                break
            page.wait_for_timeout(150)
        assert len(goals) >= 2 and "greedy error over the 4 goals" in overlay(page)
        assert screenshot(page, tmp_path, "viewer-train-reach2.png").std() > 10
        view.close()
        page.wait_for_function("() => document.getElementById('somarm-panel').innerText.includes("
                               "'connection closed')")
        assert page.foreign_requests == []
        page.close()


def test_a_browser_that_connects_late_gets_the_whole_scene(browser, server):
    show = ArmShow(load_model("arm2"), prefix="/meshcat/late")
    client = MeshcatClient(server.zmq_url, timeout_s=10)
    client.send_batch(show.setup())
    client.send(show.text(title="late: the whole scene"))
    first = open_page(browser, server.web_url)
    first.wait_for_function("() => typeof viewer !== 'undefined' && viewer.scene.getObjectByName('link2')")
    client.send_batch(show.frame(np.array([0.3, 0.6]), np.array([2.0, -0.5])))
    second = open_page(browser, server.web_url)
    second.wait_for_function("() => typeof viewer !== 'undefined' && viewer.scene.getObjectByName('link2')")
    settle(second)
    for page in (first, second):
        settle(page)
        got = drawn_pose(page, ["meshcat", "late"], "link1/link1")
        expected = mujoco_pose(show.model, np.array([2.0, -0.5]), np.array([[0.3, 0.6, 0.0]]), "link1")
        np.testing.assert_allclose(got, expected, atol=1e-5)
        assert overlay(page).startswith("late: the whole scene") and "grid 0.2" in overlay(page)
        page.close()
    client.close()


def test_reach20_sweep_and_throw_fan_render(browser, server, tmp_path):
    """The two figure views: Fig. 11's postures and Fig. 17's fan, drawn and not blank."""
    rng = np.random.default_rng(0)
    arm20 = load_model("arm20")
    sweep = SweepShow(arm20, 7, prefix="/meshcat/reach20")
    angles = np.linspace(-0.6, 0.6, 7)
    actions = np.column_stack([np.pi / 2 + angles - 0.8] + [np.full(7, 0.08) + 0.01 * rng.normal(size=7)] * 19)
    goals = np.column_stack([0.5 + 0.25 * np.cos(np.pi / 2 + angles), 0.5 + 0.25 * np.sin(np.pi / 2 + angles)])
    client = MeshcatClient(server.zmq_url, timeout_s=10)
    client.send_batch(sweep.setup() + sweep.frame(goals, actions))
    page = open_page(browser, server.web_url)
    page.wait_for_function("() => typeof viewer !== 'undefined' && viewer.scene.getObjectByName('posture06')")
    settle(page)
    got = drawn_pose(page, ["meshcat", "reach20"], "posture03/link20/link20")
    expected = mujoco_pose(arm20, actions[3], np.array([[*goals[3], 0.0]]), "link20")
    np.testing.assert_allclose(got, expected, atol=1e-5)
    assert screenshot(page, tmp_path, "viewer-reach20.png").std() > 10
    page.close()

    launcher = load_model("launcher")
    fan = np.column_stack([np.linspace(0.35, 0.2, 6), np.linspace(0.2, 0.8, 6)])
    throw = ThrowShow(launcher, simulate_trajectory, n_balls=6)
    client.send(Delete(path_of("/meshcat/reach20")).lower())
    client.send_batch(throw.setup() + throw.throw_commands(fan, 4.0))
    page = open_page(browser, server.web_url)
    page.wait_for_function("() => typeof viewer !== 'undefined' && viewer.scene.getObjectByName('trail05')")
    page.wait_for_timeout(1500)  # let the balls fly a while
    assert screenshot(page, tmp_path, "viewer-throw.png").std() > 10
    assert page.foreign_requests == []
    page.close()
    client.close()


def test_the_static_html_opens_without_a_server_animates_and_says_what_it_shows(browser, tmp_path):
    from somarm.viewer.sessions import arm_animation

    show = ArmShow(load_model("arm2"), prefix="/meshcat/offline")
    goals, actions = np.array([[0.4, 0.5], [0.7, 0.6]]), np.array([[1.2, 0.8], [0.3, 1.5]])
    recorder = Recorder()
    recorder.send_batch(show.setup() + show.frame(goals[0], actions[0]))
    animation, timeline = arm_animation(show, goals, actions)
    recorder.send(show.text(title="reach2: greedy answer for each goal"))
    recorder.send(timeline.command())
    recorder.send(animation)
    path = write_html(tmp_path / "offline.html", recorder.commands(), title="reach2")
    page = open_page(browser, path.as_uri())
    page.wait_for_function("() => typeof viewer !== 'undefined' && viewer.scene.getObjectByName('link2')")
    settle(page)
    assert page.title() == "reach2" and page.evaluate("() => viewer.animator.playing")
    # The animation holds goal 0 for its first frames: the page shows MuJoCo's pose for it, and says so.
    page.evaluate("() => { viewer.animator.pause(); viewer.animator.seek(0.1); }")
    settle(page)
    expected = mujoco_pose(show.model, actions[0], np.array([[*goals[0], 0.0]]), "link2")
    np.testing.assert_allclose(drawn_pose(page, ["meshcat", "offline"], "link2/link2"), expected, atol=1e-5)
    first = overlay(page)
    assert first.startswith("reach2: greedy answer for each goal") and "goal 1 of 2 at (0.400, 0.500)" in first
    # ... and goal 1's pose and its own error once the clip reaches it (frame 24 + 12 at 30 fps = 1.2 s).
    page.evaluate("() => viewer.animator.seek(1.25)")
    settle(page)
    expected = mujoco_pose(show.model, actions[1], np.array([[*goals[1], 0.0]]), "link2")
    np.testing.assert_allclose(drawn_pose(page, ["meshcat", "offline"], "link2/link2"), expected, atol=1e-5)
    second = overlay(page)
    show.frame(goals[1], actions[1])
    assert "goal 2 of 2 at (0.700, 0.600)" in second and f"error {number(show.last_error)}" in second
    assert first.split("error ")[1] != second.split("error ")[1]  # the number changed with the scene
    assert screenshot(page, tmp_path, "offline.png").std() > 10
    assert page.foreign_requests == []
    page.close()


@pytest.mark.parametrize("task_name, task_set", [("reach2_obstacle", {}), ("reach2", {"dynamics": "actuated"})])
def test_driven_arms_move_along_mujocos_trajectory_in_the_exported_page(browser, tmp_path, task_name, task_set):
    from somarm.viewer import sessions

    session = sessions.load_session(task_name, n_goals=2, seed=0, task_set=task_set)
    recorder = Recorder()
    sessions.record(session, recorder)
    path = write_html(tmp_path / f"{task_name}.html", recorder.commands(), title=task_name)
    page = open_page(browser, path.as_uri())
    page.wait_for_function("() => typeof viewer !== 'undefined' && viewer.scene.getObjectByName('link2')")
    settle(page)
    assert page.evaluate("() => viewer.animator.playing")
    root = ["meshcat", task_name]
    model = session.show.model
    mocap = np.array([[*session.observations[0][:2], 0.0]] * model.nmocap).reshape(model.nmocap, 3)
    # At 50 frames a second, frame k (time k / 50 s) is timestep 2k of the first path.
    page.evaluate("() => viewer.animator.pause()")
    said = []
    for k in (0, 10):
        page.evaluate(f"() => viewer.animator.seek({k / 50.0})")
        settle(page)
        expected = mujoco_pose(model, session.paths[0][2 * k], mocap if model.nmocap else None, "link2")
        np.testing.assert_allclose(drawn_pose(page, root, "link2/link2"), expected, atol=1e-5)
        said.append(overlay(page))
    assert said[0].startswith(f"{task_name}: ") and said[0] != said[1]
    if task_name == "reach2_obstacle":
        assert "episode 1 of 2: step 0 of" in said[0] and "episode 1 of 2: step 1 of" in said[1]
        assert "fingertip's path" in said[0]
    else:
        assert "t = 0.00 s" in said[0] and "t = 0.20 s" in said[1]
    assert screenshot(page, tmp_path, f"viewer-{task_name}.png").std() > 10
    page.close()


def test_a_gymnasium_mujoco_environment_is_drawn_and_moves(browser, tmp_path):
    gymnasium = pytest.importorskip("gymnasium", reason="gymnasium (the peers extra) is not installed")
    from somarm.viewer.model_view import rollout, view_states

    env = gymnasium.make("Reacher-v5")
    states = rollout(env, n_steps=50, seed=2)
    model = env.unwrapped.model
    path = view_states(model, states.qpos, timestep=states.timestep, title="Reacher-v5",
                       html=tmp_path / "reacher.html")
    env.close()
    page = open_page(browser, path.as_uri())
    page.wait_for_function("() => typeof viewer !== 'undefined' && viewer.scene.getObjectByName('fingertip')")
    settle(page)
    assert page.title() == "Reacher-v5" and overlay(page).startswith("Reacher-v5")
    page.evaluate("() => viewer.animator.pause()")
    for k in (0, 30):
        page.evaluate(f"() => viewer.animator.seek({k * states.timestep})")
        settle(page)
        for body, geom in (("body1", "link1"), ("fingertip", "fingertip"), ("target", "target")):
            expected = mujoco_pose(model, states.qpos[k], None, geom)
            np.testing.assert_allclose(drawn_pose(page, ["meshcat", "model"], f"{body}/{geom}"), expected,
                                       atol=1e-5, err_msg=f"{geom} at state {k}")
        assert f"state {k + 1} of 51" in overlay(page)
    pixels = screenshot(page, tmp_path, "reacher.png")
    page.evaluate("() => { viewer.scene_tree.find(['meshcat', 'model']).object.visible = false; "
                  "viewer.set_dirty(); }")
    settle(page)
    hidden = screenshot(page, tmp_path, "reacher-hidden.png")
    assert pixels.std() > 10 and (np.abs(pixels - hidden).sum(axis=2) > 30).mean() > 0.01
    assert page.foreign_requests == []
    page.close()
