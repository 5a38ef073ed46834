"""The package as a user installs it: every subpackage is listed, and the models ship with it."""

import re
import sys
from pathlib import Path

if sys.version_info >= (3, 11):
    import tomllib
else:  # Python 3.10, which the README supports: the test extra installs tomli there
    import tomli as tomllib


ROOT = Path(__file__).resolve().parents[1]


def _pyproject() -> dict:
    return tomllib.loads((ROOT / "pyproject.toml").read_text())


def test_every_subpackage_and_the_models_are_packaged():
    config = _pyproject()["tool"]["setuptools"]
    on_disk = {".".join(p.parent.relative_to(ROOT).parts) for p in (ROOT / "somarm").rglob("__init__.py")}
    assert on_disk | {"somarm.models"} == set(config["packages"])
    assert config["package-dir"]["somarm.models"] == "models"
    assert config["package-data"]["somarm.models"] == ["*.xml"]
    assert {"arm2.xml", "arm20.xml", "launcher.xml"} <= {p.name for p in (ROOT / "models").glob("*.xml")}


def test_every_data_file_of_the_package_is_package_data():
    # A file the code reads beside its module (the viewer's page.js, the reproduction's durations.json)
    # ships only when package-data names it: a wheel without it would fail where a clone works.
    import fnmatch

    data = _pyproject()["tool"]["setuptools"]["package-data"]
    files = [p for p in (ROOT / "somarm").rglob("*") if p.is_file() and p.suffix not in (".py", ".pyc")
             and "__pycache__" not in p.parts]
    assert files
    for path in files:
        package = ".".join(path.parent.relative_to(ROOT).parts)
        assert any(fnmatch.fnmatch(path.name, pattern) for pattern in data.get(package, [])), path


def test_license_is_an_spdx_string_with_a_setuptools_that_reads_it_and_a_license_file():
    project = _pyproject()
    assert project["project"]["license"] == "MIT"
    # A string `license` (an SPDX expression) is an error before setuptools 77.
    (requirement,) = [r for r in project["build-system"]["requires"] if r.startswith("setuptools")]
    minimum = re.fullmatch(r"setuptools>=(\d+)(?:\.\d+)*", requirement)
    assert minimum is not None and int(minimum.group(1)) >= 77, requirement
    text = (ROOT / "LICENSE").read_text()
    assert text.startswith("MIT License") and "WITHOUT WARRANTY" in text
    assert project["project"]["license-files"] == ["LICENSE"]


def test_the_library_on_a_headless_machine_prints_no_glfw_warning():
    import os
    import subprocess

    env = {k: v for k, v in os.environ.items() if k not in ("MUJOCO_GL", "DISPLAY", "WAYLAND_DISPLAY")}
    env["PYTHONPATH"] = str(ROOT)
    code = ("import os; from somarm import run; "
            "run.make(run.RunConfig(task='reach2').resolved()); print(os.environ['MUJOCO_GL'])")
    done = subprocess.run([sys.executable, "-W", "default", "-c", code], env=env, capture_output=True, text=True,
                          timeout=120)
    assert done.returncode == 0 and done.stdout.strip() == "disable", done.stderr
    assert "GLFW" not in done.stderr and "DISPLAY" not in done.stderr, done.stderr
    env["MUJOCO_GL"] = "egl"  # a user's own choice is kept
    done = subprocess.run([sys.executable, "-c", "import os, somarm; print(os.environ['MUJOCO_GL'])"], env=env,
                          capture_output=True, text=True, timeout=60)
    assert done.stdout.strip() == "egl"


def test_the_version_is_written_once_and_packaging_reads_it_from_the_package():
    import pytest

    import somarm

    project = _pyproject()["project"]
    assert "version" not in project and project["dynamic"] == ["version"]
    assert _pyproject()["tool"]["setuptools"]["dynamic"]["version"] == {"attr": "somarm.__version__"}
    pyprojecttoml = pytest.importorskip("setuptools.config.pyprojecttoml")
    expanded = pyprojecttoml.read_configuration(ROOT / "pyproject.toml", expand=True)
    assert expanded["project"]["version"] == somarm.__version__
    assert re.fullmatch(r"\d+\.\d+\.\d+", somarm.__version__)


def test_the_default_output_folders_are_ignored_by_git(tmp_path):
    import shutil
    import subprocess

    assert shutil.which("git"), "git is needed to check .gitignore"
    for folder in ("runs/reach2__somq__seed0", "compare/reach2", "sweeps/reach2", "reproduce", "reproduce-quick"):
        done = subprocess.run(["git", "check-ignore", "-q", f"{folder}/x.json"], cwd=ROOT)
        assert done.returncode == 0, f"{folder} is not ignored by .gitignore"
