"""CI cannot go green by skipping: with CI=true a skipped test fails (tests/conftest.py); .ci/run is strict
and runs the README's test command, with every extra."""

import importlib.util
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

if sys.version_info >= (3, 11):
    import tomllib
else:  # Python 3.10: the test extra installs tomli there
    import tomli as tomllib

ROOT = Path(__file__).resolve().parents[1]

SKIPPING = {
    "test_inside.py": "import pytest\n\ndef test_needs_chromium():\n    pytest.skip('no chromium')\n",
    "test_module.py": "import pytest\n\npytest.importorskip('no_such_extra_xyz')\n\ndef test_x():\n    pass\n",
}


@pytest.mark.parametrize("name", sorted(SKIPPING))
@pytest.mark.parametrize("ci", ["true", ""])
def test_a_skip_fails_only_in_ci(name, ci, tmp_path):
    shutil.copy(ROOT / "tests" / "conftest.py", tmp_path / "conftest.py")
    (tmp_path / name).write_text(SKIPPING[name])
    env = {k: v for k, v in os.environ.items() if k != "CI"} | {"CI": ci}
    done = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", name],
                          cwd=tmp_path, env=env, capture_output=True, text=True, timeout=60)
    if ci:
        assert done.returncode != 0 and "skipped in CI" in done.stdout, done.stdout
    else:
        # 5: no test ran (the whole module was skipped), which pytest does not count as failed
        assert done.returncode in (0, 5) and "1 skipped" in done.stdout, done.stdout


def test_ci_script_fails_without_chromium_and_installs_no_driver():
    script = (ROOT / ".ci" / "run").read_text()
    assert "chromium-driver" not in script
    assert "export CI=true" in script
    assert "exit 1" in script and "warning: chromium install failed" not in script


TEST_COMMAND = re.compile(r"^python3 -m venv \.venv && .*\.venv/bin/pytest$", re.M)


def test_ci_runs_the_readmes_test_command_verbatim_and_the_docs_repeat_it():
    (in_ci,) = TEST_COMMAND.findall((ROOT / ".ci" / "run").read_text())
    assert TEST_COMMAND.findall((ROOT / "README.md").read_text()) == [in_ci]
    assert TEST_COMMAND.findall((ROOT / "docs" / "install.md").read_text()) == [in_ci]
    # every extra is installed, so CI skips nothing (the site's build needs `docs`)
    extras = re.search(r'-e "\.\[([a-z,]+)\]"', in_ci).group(1).split(",")
    assert set(extras) == set(tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["optional-dependencies"])


def _front_door():
    spec = importlib.util.spec_from_file_location("front_door", ROOT / ".ci" / "front_door.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_readme_keeps_the_one_line_set_up_and_reproduction_on_its_first_screen():
    text = (ROOT / "README.md").read_text()
    command = "python3 -m venv .venv && .venv/bin/pip install -q -e . && .venv/bin/somarm reproduce --quick"
    first = next(i for i, line in enumerate(text.splitlines()) if line.startswith("```"))
    assert first < 50 and text.splitlines()[first + 1].startswith(command)
    assert "\n.venv/bin/somarm reproduce --out reproduce\n" in text  # the full run, on its own line


def test_ci_follows_the_readmes_front_door_its_install_line_quick_run_and_every_python_example():
    front_door = _front_door()
    text = (ROOT / "README.md").read_text()
    marked = front_door.blocks(text)
    fences = re.findall(r"^```(\w+)\n(.*?)^```", text, re.S | re.M)
    assert marked[0] == fences[0]  # the first command a reader meets
    assert "reproduce --quick" in marked[0][1]
    python = [block for block in fences if block[0] == "python"]
    assert python and all(block in marked for block in python)  # no example can drift
    assert all(language in ("bash", "python") for language, _ in marked)
    # CI runs it, as its own step after the suite (not inside pytest's default run).
    script = (ROOT / ".ci" / "run").read_text()
    assert script.rstrip().endswith("python3 .ci/front_door.py")


def test_the_front_door_stops_at_the_first_failing_block(tmp_path, capsys):
    front_door = _front_door()
    (tmp_path / "README.md").write_text(
        "<!-- front door -->\n```bash\necho one > one.txt\n```\n\n<!-- front door -->\n```bash\nexit 3\n```\n"
        "\n<!-- front door -->\n```bash\necho three > three.txt\n```\n")
    assert front_door.run(tmp_path) == 3
    assert (tmp_path / "one.txt").is_file() and not (tmp_path / "three.txt").exists()
    assert "front door 2/3: exit 3" in capsys.readouterr().out
