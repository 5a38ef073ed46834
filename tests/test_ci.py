"""CI cannot go green by skipping: with CI=true a skipped test fails (tests/conftest.py); .ci/run is strict
and runs the README's test command, with every extra."""

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


def test_the_readme_keeps_the_one_line_set_up_and_reproduction():
    command = "python3 -m venv .venv && .venv/bin/pip install -q -e . && .venv/bin/somarm reproduce --out reproduce"
    assert f"\n{command}\n" in (ROOT / "README.md").read_text()
