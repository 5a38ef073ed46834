"""MJCF geoms -> meshcat objects and poses, checked against MuJoCo without any server."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import mujoco
import numpy as np
import pytest
import umsgpack

from somarm.viewer import overlays
from somarm.viewer.client import Recorder
from somarm.viewer.html import static_html, write_html
from somarm.viewer.scene import MujocoScene, geom_parts, geom_transforms

MODELS = Path(__file__).resolve().parents[2] / "models"

# Every geom type the viewer draws, on a 2-link arm and a free body, tilted so no axis is trivial.
SHAPES_XML = """
<mujoco model="shapes">
  <worldbody>
    <geom name="floor" type="plane" size="2 3 0.1" rgba="0.8 0.8 0.8 1"/>
    <geom name="endless" type="plane" size="0 0 1" pos="0 0 -1"/>
    <body name="upper" pos="0.1 0.2 0.3" euler="0.3 -0.2 0.5">
      <joint name="shoulder" type="hinge" axis="0 0 1"/>
      <geom name="upper" type="capsule" fromto="0 0 0 0.4 0 0" size="0.02"/>
      <body name="lower" pos="0.4 0 0">
        <joint name="elbow" type="hinge" axis="0 1 1"/>
        <geom name="lower" type="capsule" fromto="0 0 0 0.3 0.1 0" size="0.015"/>
        <geom name="hand" type="box" pos="0.3 0.1 0" size="0.03 0.02 0.01" euler="0.1 0.2 0.3"/>
        <site name="fingertip" pos="0.3 0.1 0"/>
      </body>
    </body>
    <body name="free" pos="1 0 1">
      <freejoint/>
      <geom name="ball" type="sphere" size="0.05"/>
      <geom name="can" type="cylinder" size="0.04 0.1" pos="0.2 0 0" euler="0.4 0.1 0"/>
      <geom name="egg" type="ellipsoid" size="0.05 0.03 0.02" pos="0 0.2 0"/>
    </body>
  </worldbody>
</mujoco>
"""


def shapes_model() -> mujoco.MjModel:
    return mujoco.MjModel.from_xml_string(SHAPES_XML)


def random_qpos(model: mujoco.MjModel, rng: np.random.Generator) -> np.ndarray:
    qpos = model.qpos0 + rng.uniform(-2.0, 2.0, model.nq)
    for j in np.flatnonzero(model.jnt_type == mujoco.mjtJoint.mjJNT_FREE):
        adr = model.jnt_qposadr[j]
        qpos[adr + 3 : adr + 7] /= np.linalg.norm(qpos[adr + 3 : adr + 7])
    return qpos


def mujoco_poses(model: mujoco.MjModel, qpos: np.ndarray) -> np.ndarray:
    """Reference: a fresh MjData through the full mj_forward, geom poses as 4x4."""
    data = mujoco.MjData(model)
    data.qpos[:] = qpos
    mujoco.mj_forward(model, data)
    out = np.tile(np.eye(4), (model.ngeom, 1, 1))
    out[:, :3, :3] = data.geom_xmat.reshape(-1, 3, 3)
    out[:, :3, 3] = data.geom_xpos
    return out


def model_files() -> list[Path]:
    return [MODELS / f"{name}.xml" for name in ("arm2", "arm20", "launcher") if (MODELS / f"{name}.xml").exists()]


def drawn_geom_poses(scene: MujocoScene, commands: list[dict]) -> dict[str, np.ndarray]:
    """What the page composes for each geom: its body's transform times the geom's own (from the commands)."""
    sent = {c["path"]: np.array(c["matrix"]).reshape(4, 4).T for c in commands if c["type"] == "set_transform"}
    out = {}
    for name in scene.names:
        node = scene.node(name).lower()
        out[name] = sent[node.rsplit("/", 1)[0]] @ sent[node]
    return out


@pytest.mark.parametrize("source", ["shapes", *[p.name for p in model_files()]])
def test_each_geom_pose_equals_mujoco(source):
    model = shapes_model() if source == "shapes" else mujoco.MjModel.from_xml_path(str(MODELS / source))
    scene = MujocoScene(model, prefix="/meshcat/test")
    setup = scene.setup_commands()
    rng = np.random.default_rng(3)
    for _ in range(5):
        qpos = random_qpos(model, rng)
        mocap = rng.uniform(-1, 1, (model.nmocap, 3))
        data = mujoco.MjData(model)
        data.qpos[:] = qpos
        data.mocap_pos[:] = mocap
        mujoco.mj_forward(model, data)
        expected = np.tile(np.eye(4), (model.ngeom, 1, 1))
        expected[:, :3, :3] = data.geom_xmat.reshape(-1, 3, 3)
        expected[:, :3, 3] = data.geom_xpos
        np.testing.assert_allclose(scene.geom_poses(qpos, mocap_pos=mocap), expected[scene.geom_ids], atol=1e-9)
        # What goes over the wire (column-major, as three.js reads it): body poses, geoms fixed in them.
        drawn = drawn_geom_poses(scene, setup + scene.pose_commands(qpos, mocap_pos=mocap, everything=True))
        for k, name in enumerate(scene.names):
            np.testing.assert_allclose(drawn[name], expected[scene.geom_ids[k]], atol=1e-9, err_msg=name)


def test_a_state_may_be_an_mjdata_straight_after_a_step():
    model = shapes_model()
    scene = MujocoScene(model, prefix="/m")
    data = mujoco.MjData(model)
    data.qvel[:] = 3.0
    for _ in range(4):
        mujoco.mj_step(model, data)  # data.xpos now lags qpos by a step; the scene recomputes them
    np.testing.assert_allclose(scene.transforms(data), scene.transforms(data.qpos.copy()), atol=0)
    reference = mujoco.MjData(model)
    reference.qpos[:] = data.qpos
    mujoco.mj_kinematics(model, reference)
    np.testing.assert_allclose(scene.transforms(data)[:, :3, 3], reference.xpos[scene.body_ids], atol=1e-12)
    assert np.abs(scene.transforms(data)[:, :3, 3] - data.xpos[scene.body_ids]).max() > 1e-3


def test_a_gymnasium_mujoco_environment_is_drawn_from_its_model():
    gymnasium = pytest.importorskip("gymnasium", reason="gymnasium (the peers extra) is not installed")
    env = gymnasium.make("Reacher-v5")
    base = env.unwrapped
    env.reset(seed=0)
    for _ in range(5):
        env.step(env.action_space.sample())
    scene = MujocoScene(base.model, prefix="/meshcat/reacher")
    assert {"ground", "link0", "link1", "fingertip", "target"} <= set(scene.names)
    assert {"body0", "body1", "fingertip", "target"} <= set(scene.body_names)
    drawn = drawn_geom_poses(scene, scene.setup_commands() + scene.pose_commands(base.data, everything=True))
    mujoco.mj_kinematics(base.model, base.data)
    for k, name in enumerate(scene.names):
        geom = scene.geom_ids[k]
        np.testing.assert_allclose(drawn[name][:3, 3], base.data.geom_xpos[geom], atol=1e-9, err_msg=name)
        np.testing.assert_allclose(drawn[name][:3, :3], base.data.geom_xmat[geom].reshape(3, 3), atol=1e-9)
    env.close()


def test_real_arm_fingertip_and_reach_poses_match_kinematics():
    model = mujoco.MjModel.from_xml_path(str(MODELS / "arm2.xml"))
    scene = MujocoScene(model, prefix="/meshcat/arm2")
    theta = np.array([0.7, -1.1])
    poses = dict(zip(scene.names, scene.geom_poses(theta), strict=True))
    # link2's capsule centre lies halfway along link 2, whatever the link lengths are.
    elbow = poses["link1"][:3, 3] * 2 - np.array([0.5, 0.0, 0.0])
    direction = np.array([np.cos(theta.sum()), np.sin(theta.sum()), 0.0])
    half = model.geom_size[scene.geom_ids[scene.names.index("link2")], 1]
    np.testing.assert_allclose(poses["link2"][:3, 3], elbow + half * direction, atol=1e-9)
    # The capsule's axis (its z, whichever way fromto points it) lies along the link.
    assert np.isclose(abs(poses["link2"][:3, 2] @ direction), 1.0, atol=1e-12)


def test_poses_are_read_after_kinematics_not_a_step_behind():
    model = shapes_model()
    data = mujoco.MjData(model)
    data.qvel[:] = 5.0
    mujoco.mj_step(model, data)  # qpos moved; geom_xpos still holds the pose before the step
    stale = data.geom_xpos.copy()
    fresh = geom_transforms(model, data)[:, :3, 3]
    np.testing.assert_allclose(fresh, mujoco_poses(model, data.qpos)[:, :3, 3], atol=1e-12)
    assert np.abs(fresh - stale).max() > 1e-3


def test_capsule_is_a_cylinder_along_z_and_two_caps_with_full_sizes():
    model = shapes_model()
    gid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, "lower")
    radius, half = model.geom_size[gid, :2]
    assert np.isclose(half, np.hypot(0.3, 0.1) / 2)
    parts = {p.name: p for p in geom_parts(model, gid)}
    assert set(parts) == {"cylinder", "cap0", "cap1"}
    cylinder = parts["cylinder"].geometry.lower(None)
    assert cylinder["type"] == "CylinderGeometry"
    assert np.isclose(cylinder["height"], 2 * half) and np.isclose(cylinder["radiusTop"], radius)
    pose = geom_transforms(model, mujoco.MjData(model))[gid]
    world = pose @ parts["cylinder"].local
    np.testing.assert_allclose(world[:3, 1], pose[:3, 2], atol=1e-12)  # three.js y axis = MuJoCo z axis
    for name, sign in (("cap0", -1), ("cap1", 1)):
        assert np.isclose(parts[name].geometry.lower(None)["radius"], radius)
        np.testing.assert_allclose((pose @ parts[name].local)[:3, 3], pose[:3, 3] + sign * half * pose[:3, 2])


def test_half_sizes_become_full_sizes():
    model = shapes_model()

    def lowered(name):
        gid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, name)
        return gid, geom_parts(model, gid)

    gid, (box,) = lowered("hand")
    got = box.geometry.lower(None)
    np.testing.assert_allclose([got["width"], got["height"], got["depth"]], 2 * model.geom_size[gid])
    gid, (can,) = lowered("can")
    assert np.isclose(can.geometry.lower(None)["height"], 2 * model.geom_size[gid, 1])
    np.testing.assert_allclose(can.local[:3, 1], [0, 0, 1])
    gid, (egg,) = lowered("egg")
    np.testing.assert_allclose(np.diag(egg.local)[:3], model.geom_size[gid])
    gid, (floor,) = lowered("floor")
    got = floor.geometry.lower(None)
    assert (got["width"], got["height"]) == (4.0, 6.0)
    _, (endless,) = lowered("endless")
    assert endless.geometry.lower(None)["width"] > 0  # an infinite plane is drawn finite


def test_setup_draws_every_part_and_frames_move_only_moving_bodies():
    model = shapes_model()
    scene = MujocoScene(model, prefix="/meshcat/shapes")
    setup = scene.setup_commands()
    objects = [c["path"] for c in setup if c["type"] == "set_object"]
    assert len(objects) == sum(len(scene.parts[int(g)]) for g in scene.geom_ids) == 12
    assert "/meshcat/shapes/upper/upper/cap1" in objects and "/meshcat/shapes/world/floor/shape" in objects
    moved = {c["path"].rsplit("/", 1)[1] for c in scene.pose_commands(random_qpos(model, np.random.default_rng(0)))}
    assert moved == {"upper", "lower", "free"}
    hidden = MujocoScene(model, prefix="/m", hidden=("floor", "egg"))
    assert "floor" not in hidden.names and "egg" not in hidden.names and "ball" in hidden.names
    with pytest.raises(ValueError, match="qpos must have shape"):
        scene.transforms(np.zeros(3))
    with pytest.raises(ValueError, match="mocap_pos must have shape"):
        scene.set_state(None, mocap_pos=np.zeros((2, 3)))


def test_colours_come_from_the_model():
    model = shapes_model()
    scene = MujocoScene(model, prefix="/m")
    floor = next(c for c in scene.setup_commands() if c["path"] == "/m/world/floor/shape" and c["type"] == "set_object")
    assert floor["object"]["materials"][0]["color"] == (204 << 16) | (204 << 8) | 204


def test_segment_joins_its_ends_and_animation_recomposes_the_pose():
    rng = np.random.default_rng(1)
    start, end = rng.normal(size=3), rng.normal(size=3)
    matrix = overlays.segment_matrix(start, end)
    np.testing.assert_allclose(matrix @ [0, 0.5, 0, 1], [*end, 1], atol=1e-12)
    np.testing.assert_allclose(matrix @ [0, -0.5, 0, 1], [*start, 1], atol=1e-12)
    from meshcat.commands import SetTransform

    from somarm.viewer.scene import path_of

    command = SetTransform(matrix, path_of("/a/b")).lower()
    (animation,) = overlays.animation_command([[command], [command]], fps=10)["animations"]
    tracks = {t["name"]: t["keys"][1]["value"] for t in animation["clip"]["tracks"]}
    x, y, z, w = tracks[".quaternion"]
    import meshcat.transformations as tf

    rebuilt = tf.quaternion_matrix([w, x, y, z]) @ np.diag([*tracks[".scale"], 1.0])
    rebuilt[:3, 3] = tracks[".position"]
    np.testing.assert_allclose(rebuilt, matrix, atol=1e-9)


def test_static_html_holds_the_viewer_and_every_command(tmp_path):
    recorder = Recorder()
    scene = MujocoScene(shapes_model(), prefix="/meshcat/shapes")
    recorder.send_batch(scene.setup_commands() + scene.pose_commands(everything=True))
    path = write_html(tmp_path / "scene.html", recorder.commands(), title="shapes")
    text = path.read_text()
    assert "MeshCat.Viewer" in text and "<title>shapes</title>" in text
    import base64
    import json
    import re

    encoded = json.loads(re.search(r"var commands = (\[.*?\]);", text).group(1))
    assert [umsgpack.unpackb(base64.b64decode(e)) for e in encoded] == recorder.commands()
    page = static_html([])
    assert page.count("<script") == 3  # meshcat's viewer, the overlay, the replay
    assert "SomarmOverlay.install(viewer)" in page and 'id="meshcat-pane"' in page
    assert "<title>a &lt;b&gt;</title>" in static_html([], title="a <b>")
    with pytest.raises(ValueError, match="does not exist"):
        write_html(tmp_path / "missing" / "x.html", [])


def test_importing_somarm_does_not_import_meshcat():
    import subprocess
    import sys

    code = "import sys, somarm, somarm.cli, somarm.run.loop, somarm.tasks; print('meshcat' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "False"
    assert importlib.util.find_spec("somarm.viewer.scene") is not None
