"""The shape of the reproduction's code: short experiment functions, matplotlib in one place, no history."""

import ast
import re
from pathlib import Path

import somarm

PACKAGE = Path(somarm.__file__).parent
REPRODUCE = PACKAGE / "reproduce"
MAX_LINES = 60


def _long_functions(source: str, limit: int) -> list[tuple[str, int]]:
    """(name, lines) of every function or method in ``source`` longer than ``limit`` lines."""
    return [
        (node.name, node.end_lineno - node.lineno + 1)
        for node in ast.walk(ast.parse(source))
        if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef) and node.end_lineno - node.lineno + 1 > limit
    ]


def _function(n_lines: int) -> str:
    return "def f():\n" + "".join(f"    x{i} = {i}\n" for i in range(n_lines - 1))


def test_the_length_check_finds_a_long_function_and_passes_a_short_one():
    assert _long_functions(_function(MAX_LINES + 1), MAX_LINES) == [("f", MAX_LINES + 1)]
    assert _long_functions(_function(MAX_LINES), MAX_LINES) == []


def test_no_function_in_the_reproduction_is_over_sixty_lines():
    long = [f"{path.name}: {name} ({lines} lines)" for path in sorted(REPRODUCE.glob("*.py"))
            for name, lines in _long_functions(path.read_text(), MAX_LINES)]
    assert not long, f"split these into train, measure and report parts: {long}"


def _matplotlib_users(path: Path) -> list[str]:
    """How ``path`` reaches matplotlib other than by calling ``somarm.plots.pyplot`` itself."""
    found = []
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            found += [alias.name for alias in node.names if alias.name.split(".")[0] == "matplotlib"]
        elif isinstance(node, ast.ImportFrom) and node.module:
            if node.module.split(".")[0] == "matplotlib":
                found.append(f"from {node.module}")
            if node.module.split(".")[0] == "somarm" and any(alias.name == "plt" for alias in node.names):
                found.append(f"from {node.module} import plt")
        elif isinstance(node, ast.Attribute) and node.attr == "plt" and isinstance(node.value, ast.Name):
            found.append(f"{node.value.id}.plt")
    return found


def test_matplotlib_is_imported_only_by_the_headless_helper():
    users = {str(path.relative_to(PACKAGE)): used for path in sorted(PACKAGE.rglob("*.py"))
             if path.name != "plots.py" and (used := _matplotlib_users(path))}
    assert not users, f"call somarm.plots.pyplot() in the module instead: {users}"
    helper = _matplotlib_users(PACKAGE / "plots.py")
    assert helper == ["matplotlib", "matplotlib.pyplot"], helper


def test_the_check_sees_a_module_that_imports_pyplot_itself(tmp_path):
    module = tmp_path / "figure.py"
    module.write_text("import matplotlib.pyplot as plt\nfrom somarm import plots\nfig = plots.plt.figure()\n"
                      "from somarm.reproduce.figures import plt\n")
    assert sorted(_matplotlib_users(module)) == ["from somarm.reproduce.figures import plt", "matplotlib.pyplot",
                                                 "plots.plt"]


def test_the_reproduction_speaks_of_the_code_not_of_its_history():
    pattern = re.compile(r"\b(issues?|round \d+)\b", re.IGNORECASE)
    mentions = [f"{path.name}:{number}" for path in sorted(REPRODUCE.glob("*.py"))
                for number, line in enumerate(path.read_text().splitlines(), 1) if pattern.search(line)]
    assert not mentions, mentions
