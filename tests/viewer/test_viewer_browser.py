"""End to end in a real headless Chromium: the page's scene holds the model at MuJoCo's poses.

Needs Debian's ``chromium`` (``.ci/run`` installs it) and Playwright for Python; it never runs
``playwright install``. Where either is missing the tests are skipped with the reason (with CI=true
that skip is a failure, see conftest.py).
Screenshots go to the test's tmp folder; set ``SOMARM_SCREENSHOTS=docs`` to also write the
README's pictures (``docs/viewer-*.png``).
"""

from __future__ import annotations

import io
import os
import shutil
from pathlib import Path

import mujoco
import numpy as np
import pytest
from meshcat.commands import Delete, SetProperty

from somarm.tasks.throw import simulate_trajectory
from somarm.viewer.client import MeshcatClient, Recorder
from somarm.viewer.html import write_html
from somarm.viewer.scene import path_of
from somarm.viewer.server import MeshcatServer
from somarm.viewer.shows import ArmShow, SweepShow, ThrowShow, load_model

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
    """Save a PNG (and a docs copy if asked); return its pixels ``(h, w, 3)``."""
    from PIL import Image

    png = page.screenshot()
    (tmp_path / name).write_bytes(png)
    if os.environ.get("SOMARM_SCREENSHOTS"):
        target = Path(__file__).resolve().parents[2] / os.environ["SOMARM_SCREENSHOTS"] / name
        target.parent.mkdir(exist_ok=True)
        shutil.copy(tmp_path / name, target)
    return np.asarray(Image.open(io.BytesIO(png)).convert("RGB"), dtype=np.int16)


def settle(page) -> None:
    page.wait_for_function("() => typeof viewer !== 'undefined' && viewer.renderer !== undefined")
    page.evaluate("() => new Promise(done => requestAnimationFrame(() => requestAnimationFrame(done)))")


def mujoco_pose(model: mujoco.MjModel, qpos: np.ndarray, mocap_pos: np.ndarray, geom: str) -> np.ndarray:
    data = mujoco.MjData(model)
    data.qpos[:] = qpos
    data.mocap_pos[:] = mocap_pos
    mujoco.mj_forward(model, data)
    gid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, geom)
    pose = np.eye(4)
    pose[:3, :3] = data.geom_xmat[gid].reshape(3, 3)
    pose[:3, 3] = data.geom_xpos[gid]
    return pose


def test_the_page_holds_the_arm_at_mujocos_poses(browser, server, tmp_path):
    model = load_model("arm2")
    show = ArmShow(model, prefix="/meshcat/reach2")
    goal, action = np.array([0.62, 0.55]), np.array([0.9, 1.3])
    client = MeshcatClient(server.zmq_url, timeout_s=10)
    assert client.send_batch(show.setup()) and client.send_batch(show.frame(goal, action))
    page = open_page(browser, server.web_url)
    names = ["link1", "link2", "goal", "base", "link1/cylinder", "link2/cap1"]
    page.wait_for_function("() => typeof viewer !== 'undefined' && "
                           "viewer.scene.getObjectByName('link2') !== undefined")
    settle(page)
    drawn = page.evaluate(RELATIVE_POSE, [["meshcat", "reach2"], names])
    mocap = np.array([[*goal, 0.0]])
    for name in names:
        got = np.array(drawn[name]).reshape(4, 4).T  # three.js matrices are column-major
        geom, _, part = name.partition("/")
        expected = mujoco_pose(model, action, mocap, geom)
        if part:
            expected = expected @ {p.name: p.local for p in show.scene.parts[
                show.scene.geom_ids[show.scene.names.index(geom)]]}[part]
        np.testing.assert_allclose(got, expected, atol=1e-5, err_msg=name)  # float32 in the browser
    assert page.evaluate("() => viewer.renderer.getContext() !== null")

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


def test_live_view_streams_training_rows_to_the_page(browser):
    from somarm.viewer.live import LiveView

    model = load_model("arm2")
    with LiveView("reach2", max_rate_hz=1000.0, trial=1) as view:
        page = open_page(browser, view.url)
        page.wait_for_function("() => typeof viewer !== 'undefined' && viewer.scene.getObjectByName('link2')")
        for step, theta in enumerate([(0.3, 0.4), (1.1, -0.7), (2.2, 0.9)], start=1):
            observations = np.array([[0.1, 0.1], [0.5, 0.6]])
            actions = np.array([[0.0, 0.0], theta])
            view.update(step, observations, actions, np.array([-1.0, -0.2]))
            expected = mujoco_pose(model, np.array(theta), np.array([[0.5, 0.6, 0.0]]), "link2")

            def shown(expected=expected):
                drawn = page.evaluate(RELATIVE_POSE, [["meshcat", "reach2"], ["link2"]])
                return np.allclose(np.array(drawn["link2"]).reshape(4, 4).T, expected, atol=1e-5)

            page.wait_for_timeout(50)
            for _ in range(100):  # bounded: up to about 10 s per frame
                if shown():
                    break
                page.wait_for_timeout(100)
            assert shown(), f"frame {step} never reached the page"
        assert page.foreign_requests == []
        page.close()


def test_a_browser_that_connects_late_gets_the_whole_scene(browser, server):
    show = ArmShow(load_model("arm2"), prefix="/meshcat/late")
    client = MeshcatClient(server.zmq_url, timeout_s=10)
    client.send_batch(show.setup())
    first = open_page(browser, server.web_url)
    first.wait_for_function("() => typeof viewer !== 'undefined' && viewer.scene.getObjectByName('link2')")
    client.send_batch(show.frame(np.array([0.3, 0.6]), np.array([2.0, -0.5])))
    second = open_page(browser, server.web_url)
    second.wait_for_function("() => typeof viewer !== 'undefined' && viewer.scene.getObjectByName('link2')")
    settle(second)
    for page in (first, second):
        settle(page)
        drawn = page.evaluate(RELATIVE_POSE, [["meshcat", "late"], ["link1"]])
        got = np.array(drawn["link1"]).reshape(4, 4).T
        expected = mujoco_pose(show.model, np.array([2.0, -0.5]), np.array([[0.3, 0.6, 0.0]]), "link1")
        np.testing.assert_allclose(got, expected, atol=1e-5)
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
    drawn = page.evaluate(RELATIVE_POSE, [["meshcat", "reach20"], ["posture03/link20"]])
    expected = mujoco_pose(arm20, actions[3], np.array([[*goals[3], 0.0]]), "link20")
    np.testing.assert_allclose(np.array(drawn["posture03/link20"]).reshape(4, 4).T, expected, atol=1e-5)
    assert screenshot(page, tmp_path, "viewer-reach20.png").std() > 10
    page.close()

    launcher = load_model("launcher")
    fan = np.column_stack([np.linspace(0.35, 0.2, 6), np.linspace(0.2, 0.8, 6)])
    throw = ThrowShow(launcher, lambda ux, uy: simulate_trajectory(ux, uy)[1], n_balls=6)
    client.send(Delete(path_of("/meshcat/reach20")).lower())
    client.send_batch(throw.setup() + throw.throw_commands(fan, 4.0))
    page = open_page(browser, server.web_url)
    page.wait_for_function("() => typeof viewer !== 'undefined' && viewer.scene.getObjectByName('trail05')")
    page.wait_for_timeout(1500)  # let the balls fly a while
    assert screenshot(page, tmp_path, "viewer-throw.png").std() > 10
    assert page.foreign_requests == []
    page.close()
    client.close()


def test_the_static_html_opens_without_a_server_and_animates(browser, tmp_path):
    from somarm.viewer.sessions import arm_animation

    show = ArmShow(load_model("arm2"), prefix="/meshcat/offline")
    goals, actions = np.array([[0.4, 0.5], [0.7, 0.6]]), np.array([[1.2, 0.8], [0.3, 1.5]])
    recorder = Recorder()
    recorder.send_batch(show.setup() + show.frame(goals[0], actions[0]))
    recorder.send(arm_animation(show, goals, actions))
    path = write_html(tmp_path / "offline.html", recorder.commands())
    page = open_page(browser, path.as_uri())
    page.wait_for_function("() => typeof viewer !== 'undefined' && viewer.scene.getObjectByName('link2')")
    settle(page)
    assert page.evaluate("() => viewer.animator.actions.length") > 0
    assert page.evaluate("() => viewer.animator.playing")
    # The animation holds goal 0 for its first frames: the page shows MuJoCo's pose for it.
    page.evaluate("() => { viewer.animator.pause(); viewer.animator.seek(0.1); }")
    settle(page)
    drawn = page.evaluate(RELATIVE_POSE, [["meshcat", "offline"], ["link2"]])
    expected = mujoco_pose(show.model, actions[0], np.array([[*goals[0], 0.0]]), "link2")
    np.testing.assert_allclose(np.array(drawn["link2"]).reshape(4, 4).T, expected, atol=1e-5)
    # ... and goal 1's pose once the clip reaches it (frame 18 + 12 at 30 fps = 1 s).
    page.evaluate("() => viewer.animator.seek(1.05)")
    settle(page)
    drawn = page.evaluate(RELATIVE_POSE, [["meshcat", "offline"], ["link2"]])
    expected = mujoco_pose(show.model, actions[1], np.array([[*goals[1], 0.0]]), "link2")
    np.testing.assert_allclose(np.array(drawn["link2"]).reshape(4, 4).T, expected, atol=1e-5)
    assert screenshot(page, tmp_path, "offline.png").std() > 10
    assert page.foreign_requests == []
    page.close()


@pytest.mark.parametrize("task_name, task_set", [("reach2_obstacle", {}), ("reach2", {"dynamics": "actuated"})])
def test_driven_arms_move_along_mujocos_trajectory_in_the_exported_page(browser, tmp_path, task_name, task_set):
    from somarm.viewer import sessions

    session = sessions.load_session(task_name, n_goals=2, seed=0, task_set=task_set)
    recorder = Recorder()
    sessions.record(session, recorder)
    path = write_html(tmp_path / f"{task_name}.html", recorder.commands())
    page = open_page(browser, path.as_uri())
    page.wait_for_function("() => typeof viewer !== 'undefined' && viewer.scene.getObjectByName('link2')")
    settle(page)
    assert page.evaluate("() => viewer.animator.playing")
    root = ["meshcat", task_name]
    model = session.show.model
    mocap = np.array([[*session.observations[0][:2], 0.0]] * model.nmocap).reshape(model.nmocap, 3)
    # At 50 frames a second, frame k (time k / 50 s) is timestep 2k of the first path.
    page.evaluate("() => viewer.animator.pause()")
    for k in (0, 10):
        page.evaluate(f"() => viewer.animator.seek({k / 50.0})")
        settle(page)
        drawn = page.evaluate(RELATIVE_POSE, [root, ["link2"]])
        expected = mujoco_pose(model, session.paths[0][2 * k], mocap, "link2")
        np.testing.assert_allclose(np.array(drawn["link2"]).reshape(4, 4).T, expected, atol=1e-5)
    assert screenshot(page, tmp_path, f"viewer-{task_name}.png").std() > 10
    page.close()
