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
    spec = importlib.util.spec_from_file_location("docs_hooks", ROOT / "tools" / "docs_hooks.py")
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


def _claims(path: Path) -> list[dict]:
    import json

    return [c for part in json.loads(path.read_text())["experiments"].values() for c in part["claims"]]


def test_the_claim_counts_in_the_readme_and_the_home_page_are_the_reports_own():
    """Read from the committed claims files: the paper's report, and the two parts beyond the paper that
    a default `somarm reproduce` runs (driven_arm, beyond)."""
    paper = _claims(ROOT / "docs" / "reproduce" / "claims.json")
    beyond = _claims(ROOT / "docs" / "reproduce" / "driven_arm" / "claims.json") + _claims(
        ROOT / "docs" / "beyond" / "claims.json")
    seeds = {c["seeds"] for c in paper}
    assert len(seeds) == 1
    (n,) = seeds
    every = sum(c["holds_in"] == n for c in paper)
    undecided = sum(all(s["holds"] is None for s in c["per_seed"]) for c in paper)
    never = sum(all(s["holds"] is False for s in c["per_seed"]) for c in paper)
    some = sorted((c["holds_in"] for c in paper if 0 < c["holds_in"] < n), reverse=True)
    for page in (README, ROOT / "docs" / "index.md"):
        text = " ".join(page.read_text().split())
        default = re.search(r"checks (\d+) claims: the paper's (\d+) and (\d+) beyond it", text)
        assert default, f"{page.name} states the default run's claims"
        assert tuple(map(int, default.groups())) == (len(paper) + len(beyond), len(paper), len(beyond))
    text = " ".join(README.read_text().split())
    said = re.search(r"of the paper's (\d+) claims, (\d+) hold at every seed, (.*?); (\d+) are undecided and (\d+) "
                     r"do not hold at any seed", text)
    assert said, "the README states the committed report's verdicts"
    assert (int(said.group(1)), int(said.group(2)), int(said.group(4)), int(said.group(5))) == (
        len(paper), every, undecided, never)
    # The claims that hold at some seeds, each "K at H of N": as many as the report has, at the same H.
    partly = re.findall(r"(\d+) at (\d+) of (\d+)", said.group(3))
    stated = sorted((int(h) for k, h, _ in partly for _ in range(int(k))), reverse=True)
    assert stated == some and all(int(total) == n for _, _, total in partly)


def test_every_install_line_that_pulls_torch_installs_its_cpu_build_first():
    # An extra with torch in it (peers) installed without the CPU index first resolves a CUDA build of
    # several GB; every such line of the README and the docs says how, on it or on the line before.
    if sys.version_info >= (3, 11):
        import tomllib
    else:  # Python 3.10: the test extra installs tomli there
        import tomli as tomllib

    extras = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["optional-dependencies"]
    with_torch = {name for name, needs in extras.items() if any(n.startswith("torch") for n in needs)}
    assert with_torch
    for page in PAGES:
        lines = page.read_text().splitlines()
        for i, line in enumerate(lines):
            for wanted in re.findall(r"pip install [^`\n]*?\[([a-z,]+)\]", line):
                if with_torch & set(wanted.split(",")):
                    around = line + (lines[i - 1] if i else "")
                    assert "download.pytorch.org/whl/cpu" in around, f"{page.name}:{i + 1}: {line}"


def _budget_rows(path: Path) -> dict[str, list[str]]:
    """The rows of a page's budget table (its header names "SOM-Q's preset trains"), by environment."""
    text = path.read_text()
    table = text[text.index("| environment | SOM-Q's preset trains"):].split("\n\n")[0].splitlines()[2:]
    return {cells[0]: cells[1:] for cells in ([c.strip() for c in row.strip("|").split("|")] for row in table)}


@pytest.mark.parametrize("page", [README, ROOT / "docs" / "results.md"], ids=lambda p: p.name)
def test_the_budget_tables_samples_and_seconds_are_the_presets_and_the_reports(page):
    from somarm.tasks.gym_envs import BENCHMARKS

    folders = {"Pendulum-v1": "pendulum", "MountainCarContinuous-v0": "mountaincar",
               "InvertedPendulum-v5": "invertedpendulum", "Reacher-v5": "reacher"}
    rows = _budget_rows(page)
    assert set(folders) <= set(rows)
    for env_id, folder in folders.items():
        trains, seconds, ends, target = rows[env_id][:4]
        report = (ROOT / "docs" / "benchmarks" / folder / "REPORT.md").read_text()
        final, to_target, ms = re.search(rf"^\| {env_id} \| SOM-Q \| (\S+) ± \S+ \| [^|]+ \| ([^|]+) \| (\S+) \|$",
                                         report, re.M).groups()
        steps = BENCHMARKS[env_id][1]
        assert trains == f"{steps:,} samples", (env_id, trains)
        assert seconds == f"about {round(steps * float(ms) / 1000)}", (env_id, seconds, ms)
        assert ends == final, (env_id, ends, final)
        if to_target.strip() == "not reached":
            assert target.endswith("not reached"), (env_id, target)
        else:
            samples, wall = re.fullmatch(r"(\d+) samples, ([\d.]+) s", to_target.strip()).groups()
            assert target.endswith(f"after {int(samples):,} samples, {round(float(wall))} s"), (env_id, target)


def test_somqs_docstring_gives_each_benchmarks_samples_and_seconds_as_the_results_page():
    from somarm.agent import SOMQ

    rows = _budget_rows(ROOT / "docs" / "results.md")
    lines = {line.split()[0]: line for line in SOMQ.__doc__.splitlines() if line.strip()}
    for env_id in ("Pendulum-v1", "MountainCarContinuous-v0", "InvertedPendulum-v5", "Reacher-v5"):
        trains, seconds = rows[env_id][:2]
        said = lines[env_id].split()
        assert said[1] == trains.split()[0] and " ".join(said[2:4]).rstrip(";") == seconds, (env_id, said)


def test_every_command_the_readme_gives_runs_from_the_venv():
    text = README.read_text()
    commands = [part.strip() for block in re.findall(r"^```bash\n(.*?)^```", text, re.S | re.M)
                for line in block.splitlines() for part in line.split("&&") if part.strip()]
    commands += re.findall(r"`((?:pip|mkdocs|pytest|ruff|somarm) [^`]*)`", text)  # inline, as typed
    allowed = (".venv/bin/", "python3 -m venv ")
    assert commands and all(c.startswith(allowed) for c in commands if not c.startswith("somarm ")), commands


def test_no_image_on_the_pages_is_described_by_its_file_name():
    for page in PAGES:
        for alt, target in re.findall(r"!\[([^\]]*)\]\(([^)\s]+)\)", page.read_text()):
            stem = Path(target).stem
            assert alt.strip() and alt != stem and len(alt.split()) >= 3, (page.name, alt, target)
