"""The MJCF models: named parts, the documented conventions, and the generated 20-link arm."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import mujoco
import numpy as np
import pytest

from somarm.tasks import assets

ROOT = Path(__file__).resolve().parents[2]


def _model(name: str) -> mujoco.MjModel:
    return mujoco.MjModel.from_xml_path(str(assets.model_path(name)))


@pytest.mark.parametrize("name", assets.MODEL_NAMES)
def test_every_part_is_named(name):
    model = _model(name)
    kinds = {
        "body": (model.nbody, mujoco.mjtObj.mjOBJ_BODY, 1),  # body 0 is the world
        "joint": (model.njnt, mujoco.mjtObj.mjOBJ_JOINT, 0),
        "geom": (model.ngeom, mujoco.mjtObj.mjOBJ_GEOM, 0),
        "site": (model.nsite, mujoco.mjtObj.mjOBJ_SITE, 0),
        "actuator": (model.nu, mujoco.mjtObj.mjOBJ_ACTUATOR, 0),
    }
    for kind, (count, obj, first) in kinds.items():
        for i in range(first, count):
            assert mujoco.mj_id2name(model, obj, i), f"{name}: unnamed {kind} {i}"


@pytest.mark.parametrize("name, n_links", [("arm2", 2), ("arm20", 20)])
def test_arms_follow_the_conventions(name, n_links):
    model = _model(name)
    assert model.njnt == n_links
    np.testing.assert_allclose(model.body("link1").pos, [0.5, 0.0, 0.0])
    for j in range(n_links):
        joint = model.joint(f"theta{j + 1}")
        assert joint.type[0] == mujoco.mjtJoint.mjJNT_HINGE
        np.testing.assert_allclose(joint.axis, [0, 0, 1])
        np.testing.assert_allclose(joint.range, [-np.pi, np.pi], atol=1e-14)
    assert model.site("fingertip").id >= 0
    assert model.body("goal").mocapid[0] >= 0
    assert model.opt.disableflags & mujoco.mjtDisableBit.mjDSBL_CONTACT
    # Straight arm along the x-axis: the tip is the base plus the total length.
    data = mujoco.MjData(model)
    mujoco.mj_kinematics(model, data)
    reach = {2: 0.8, 20: 20 * assets.ARM20_LINK_LENGTH}[n_links]  # straight arm along x
    np.testing.assert_allclose(data.site("fingertip").xpos, [0.5 + reach, 0.0, 0.0], atol=1e-12)


def test_launcher_matches_table_3():
    model = _model("launcher")
    np.testing.assert_allclose(model.opt.gravity, [0, 0, -0.05])
    assert model.opt.integrator == mujoco.mjtIntegrator.mjINT_RK4
    assert model.body("projectile").mass[0] == 1.0
    assert model.joint("x").type[0] == mujoco.mjtJoint.mjJNT_SLIDE
    assert model.joint("height").type[0] == mujoco.mjtJoint.mjJNT_SLIDE
    assert model.dof_damping[model.joint("x").dofadr[0]] == pytest.approx(0.1)
    assert model.dof_damping[model.joint("height").dofadr[0]] == 0.0  # no vertical drag
    assert model.actuator("wind").gear[0] == pytest.approx(-0.1)
    assert model.geom("ground").type[0] == mujoco.mjtGeom.mjGEOM_PLANE
    assert model.geom("ground").pos[2] == 0.0
    assert model.body("target").mocapid[0] >= 0
    assert model.opt.disableflags & mujoco.mjtDisableBit.mjDSBL_CONTACT


def test_arm20_file_is_what_the_generator_writes():
    assert assets.model_path("arm20").read_text() == assets.arm20_xml(), (
        "models/arm20.xml differs from its generator: run python tools/make_arm20.py")


def test_make_arm20_script_check_mode():
    env = {**os.environ, "MUJOCO_GL": "disable"}
    result = subprocess.run([sys.executable, str(ROOT / "tools" / "make_arm20.py"), "--check"],
                            capture_output=True, text=True, env=env, timeout=120)
    assert result.returncode == 0, result.stdout + result.stderr
    assert "up to date" in result.stdout


def test_model_path_unknown_name_lists_the_models():
    with pytest.raises(ValueError, match="arm2, arm20, arm2_obstacle, launcher"):
        assets.model_path("arm3")


def test_model_path_falls_back_to_the_installed_package(tmp_path, monkeypatch):
    installed = tmp_path / "installed"
    installed.mkdir()
    (installed / "arm2.xml").write_text("<mujoco/>")
    monkeypatch.setattr(assets, "_SOURCE_MODELS", tmp_path / "no-checkout")
    monkeypatch.setattr(assets.importlib.resources, "files", lambda package: installed)
    assert assets.model_path("arm2") == installed / "arm2.xml"
    with pytest.raises(ValueError, match="not found"):
        assets.model_path("launcher")
