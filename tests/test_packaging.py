"""The package as a user installs it: every subpackage is listed, and the models ship with it."""

from pathlib import Path

import pytest

tomllib = pytest.importorskip("tomllib")  # Python >= 3.11


ROOT = Path(__file__).resolve().parents[1]


def test_every_subpackage_and_the_models_are_packaged():
    config = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]
    on_disk = {".".join(p.parent.relative_to(ROOT).parts) for p in (ROOT / "somarm").rglob("__init__.py")}
    assert on_disk | {"somarm.models"} == set(config["packages"])
    assert config["package-dir"]["somarm.models"] == "models"
    assert config["package-data"]["somarm.models"] == ["*.xml"]
    assert {"arm2.xml", "arm20.xml", "launcher.xml"} <= {p.name for p in (ROOT / "models").glob("*.xml")}
