"""The install command of a missing extra fits how somarm was installed, and pulls torch's CPU build."""

import json
from pathlib import Path

import pytest

from somarm import extras

ROOT = Path(__file__).resolve().parents[1]


class _Dist:
    def __init__(self, direct_url):
        self.direct_url = direct_url

    def read_text(self, name):
        return None if self.direct_url is None else json.dumps(self.direct_url)


@pytest.fixture
def installed_as(monkeypatch, tmp_path):
    """Make somarm look installed from the given distributions, its module in a folder without pyproject.toml."""
    from importlib import metadata

    monkeypatch.setattr(extras, "__file__", str(tmp_path / "site-packages" / "somarm" / "extras.py"))

    def install(*dists):
        monkeypatch.setattr(metadata, "distributions", lambda name=None: iter(dists))
    return install


def test_a_clone_installed_editable_gets_pip_install_e_of_its_folder(installed_as, tmp_path):
    installed_as(_Dist({"url": "file:///home/me/my%20somarm", "dir_info": {"editable": True}}))
    assert extras.install_command("gym") == 'pip install -e "/home/me/my somarm[gym]"'


def test_an_installed_wheel_gets_pip_install_of_the_package(installed_as):
    installed_as(_Dist(None))  # from an index: no direct_url.json
    assert extras.install_command("sweep") == "pip install 'somarm[sweep]'"
    installed_as(_Dist({"url": "file:///tmp/somarm-0.1.0-py3-none-any.whl", "archive_info": {}}))
    assert extras.install_command("sweep") == "pip install 'somarm[sweep]'"


def test_a_source_tree_run_without_installing_counts_as_a_clone(monkeypatch):
    from importlib import metadata

    monkeypatch.setattr(metadata, "distributions", lambda name=None: iter(()))
    assert extras.install_command("gym") == f'pip install -e "{ROOT}[gym]"'


def test_the_extra_that_pulls_torch_installs_its_cpu_build_first_as_the_readme_does(installed_as):
    installed_as(_Dist(None))
    command = extras.install_command("peers")
    assert command.startswith(extras.TORCH_CPU + " && pip install 'somarm[peers]'") and "docs/install.md" in command
    readme = (ROOT / "README.md").read_text()
    pin, index = extras.TORCH_CPU.split()[2], extras.TORCH_CPU.split()[-1]
    assert pin in readme and index in readme  # the same torch, from the same index


def test_a_missing_extra_is_an_import_error_and_a_value_error():
    error = extras.missing("gym", "gym: tasks need gymnasium")
    assert isinstance(error, ImportError) and isinstance(error, ValueError)
    assert str(error) == f"gym: tasks need gymnasium: {extras.install_command('gym')}"
