"""The README and the documentation site: examples that run, links that resolve, a strict build,
and a command reference that covers every command."""

import importlib.util
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"
# The hand-written pages; the generated reports live in subfolders of docs/ and are left out.
PAGES = sorted([README, *(ROOT / "docs").glob("*.md")])
#: modules of the optional extras: an example that needs a missing one is skipped (a failure in CI)
EXTRAS = {"gymnasium", "stable_baselines3", "torch", "ray"}


def _python_blocks(path: Path) -> list[str]:
    return re.findall(r"^```python\n(.*?)^```", path.read_text(), re.S | re.M)


EXAMPLES = [(path, i, block) for path in PAGES for i, block in enumerate(_python_blocks(path))]


def _hooks():
    spec = importlib.util.spec_from_file_location("docs_hooks", ROOT / "scripts" / "docs_hooks.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_readme_and_the_home_page_have_a_python_example():
    assert _python_blocks(README)
    assert _python_blocks(ROOT / "docs" / "index.md")


@pytest.mark.parametrize(("path", "index", "block"), EXAMPLES,
                         ids=[f"{p.relative_to(ROOT)}:{i}" for p, i, _ in EXAMPLES])
def test_example_runs(path, index, block, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    try:
        exec(compile(block, f"{path.relative_to(ROOT)} example {index}", "exec"), {})
    except ModuleNotFoundError as exc:
        if exc.name not in EXTRAS:
            raise
        pytest.skip(f"needs the extra that installs {exc.name}")


def test_the_readme_is_a_short_front_door_whose_links_resolve():
    text = README.read_text()
    assert len(text.splitlines()) <= 250
    targets = re.findall(r"\]\(([^)#\s]+)(?:#[^)]*)?\)", text) + re.findall(r'src="([^"]+)"', text)
    local = [t for t in targets if "://" not in t]
    assert local, "the README links to the docs"
    missing = [t for t in local if not (ROOT / t).exists()]
    assert not missing, f"README links to missing files: {missing}"


def test_the_cli_reference_covers_every_command_and_option():
    from somarm import cli

    hooks = _hooks()
    reference = hooks.cli_reference()
    sections = dict(re.findall(r"^### `(somarm[^`]*)`\n(.*?)(?=^### |\Z)", reference, re.S | re.M))
    parser = cli._parser()
    (subparsers,) = [a for a in parser._actions if hasattr(a, "_choices_actions")]
    for name, sub in subparsers.choices.items():
        titles = [t for t in sections if t == f"somarm {name}" or t.startswith(f"somarm {name} ")]
        assert titles, f"`somarm {name}` is missing from the reference"
        for title in titles:
            assert f"usage: {title} " in sections[title] or f"usage: {title}\n" in sections[title], title
        if titles == [f"somarm {name}"]:  # not a forwarding command: every option of its parser is there
            missing = [o for a in sub._actions for o in a.option_strings if o not in sections[titles[0]]]
            assert not missing, (name, missing)
    assert [t for t in sections if t.startswith("somarm bench ")] == [
        f"somarm bench {name}" for name in cli._BENCHMARKS]
    assert "--goals" in sections["somarm view"] and "--grid" in sections["somarm sweep"]


def test_a_command_that_fails_to_print_its_help_stops_the_build():
    with pytest.raises(RuntimeError, match="no_such_command"):
        _hooks().help_text(["no_such_command"])


def test_the_site_builds_strictly_with_the_generated_pages(tmp_path):
    pytest.importorskip("material", reason="needs the docs extra (mkdocs-material)")
    site = tmp_path / "site"
    done = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "-f", str(ROOT / "mkdocs.yml"),
                           "-d", str(site)], cwd=ROOT, capture_output=True, text=True, timeout=300,
                          env=os.environ | {"NO_MKDOCS_2_WARNING": "1"})
    assert done.returncode == 0, done.stdout + done.stderr
    cli_page = (site / "cli.html").read_text()
    assert "usage: somarm sweep" in cli_page and "until then" not in cli_page
    changelog = (site / "changelog.html").read_text()
    assert "0.1.0" in changelog and "Unreleased" in changelog and "included here" not in changelog
    assert (site / "reproduce" / "REPORT.html").exists()
