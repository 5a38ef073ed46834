"""The architecture page's module map names every module of the package."""

import re
from pathlib import Path

import somarm

PACKAGE = Path(somarm.__file__).parent
PAGE = PACKAGE.parent / "docs" / "architecture.md"


def _rows(text: str) -> dict[str, str]:
    """The module map's rows: the first cell's name (a package ``learners/`` or a module ``agent.py``) to the row."""
    section = text[text.index("## Module map"):text.index("## Data flow")]
    return {m.group(1): m.group(0) for m in re.finditer(r"^\| `([^`]+)` \|.*$", section, re.M)}


def test_every_module_of_the_package_is_on_the_architecture_pages_map():
    rows = _rows(PAGE.read_text())
    missing = []
    for path in sorted(PACKAGE.rglob("*.py")):
        if path.name == "__init__.py":
            continue
        parts = path.relative_to(PACKAGE).parts
        row = rows.get(parts[0] + "/") if len(parts) > 1 else rows.get(parts[0])
        if row is None or f"`{path.name}`" not in row:
            missing.append(str(path.relative_to(PACKAGE)))
    assert not missing, f"name these in docs/architecture.md's module map: {missing}"


def test_the_map_check_finds_a_module_left_out():
    page = "## Module map\n| `run/` | `loop.py` |\n| `io.py` | writes |\n## Data flow\n"
    rows = _rows(page)
    assert "`loop.py`" in rows["run/"] and "`stepper.py`" not in rows["run/"] and "io.py" in rows


def _imports(package: str) -> dict[str, set[str]]:
    """Every ``somarm`` module each module of ``somarm/<package>/`` imports, anywhere in its body."""
    import ast

    found = {}
    for path in sorted((PACKAGE / package).rglob("*.py")):
        names = set()
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Import):
                names.update(alias.name for alias in node.names)
            elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
                names.update([node.module, *(f"{node.module}.{alias.name}" for alias in node.names)])
        found[str(path.relative_to(PACKAGE))] = {n for n in names if n.startswith("somarm")}
    return found


def test_learners_and_tasks_never_import_each_other():
    for package, other in (("learners", "tasks"), ("tasks", "learners")):
        crossing = {module: sorted(n for n in names if n == f"somarm.{other}" or n.startswith(f"somarm.{other}."))
                    for module, names in _imports(package).items()}
        assert not {m: n for m, n in crossing.items() if n}, f"{package} imports {other}: {crossing}"
    # the check sees an import inside a function body too
    assert "somarm.learners.config_class" in _imports("learners")["learners/presets.py"]
