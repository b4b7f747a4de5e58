"""The code style checks, as tests: ruff (lint and format), snakefmt and Snakemake's linter."""

from __future__ import annotations

import ast
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest
from workflow_copy import ROOT

BIN = Path(sys.executable).parent


def _run(*command: str) -> subprocess.CompletedProcess:
    return subprocess.run(command, cwd=ROOT, capture_output=True, text=True, timeout=300)


@pytest.mark.parametrize(
    "command",
    [
        ("ruff", "check", "."),
        ("ruff", "format", "--check", "."),
        ("snakefmt", "--check", "Snakefile", "workflow"),
    ],
    ids=["ruff-check", "ruff-format", "snakefmt"],
)
def test_style(command):
    result = _run(str(BIN / command[0]), *command[1:])
    assert result.returncode == 0, result.stdout[-3000:] + result.stderr[-3000:]


def test_snakemake_lint():
    result = _run(str(BIN / "snakemake"), "--lint", "-n")
    assert result.returncode == 0, result.stdout[-3000:] + result.stderr[-3000:]
    assert "Lints for" not in result.stdout, result.stdout[-3000:]


def _module_imports(path: Path, modules: set[str]) -> set[str]:
    """The jointbench modules that ``path`` imports at module level."""
    found = set()
    for node in ast.parse(path.read_text()).body:
        names = []
        if isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            names = [f"{node.module}.{alias.name}" for alias in node.names] + [node.module]
        elif isinstance(node, ast.Import):
            names = [alias.name for alias in node.names]
        for name in names:
            if name in modules:
                found.add(name)
                break
    return found


def test_imports_point_downward_without_cycles():
    """The module-level import graph of jointbench has no cycle (see docs/architecture.md)."""
    paths = {
        ".".join(path.relative_to(ROOT / "src").with_suffix("").parts).removesuffix(
            ".__init__"
        ): path
        for path in (ROOT / "src" / "jointbench").rglob("*.py")
    }
    graph = {module: _module_imports(path, set(paths)) for module, path in paths.items()}
    state: dict[str, int] = {}

    def visit(module: str, trail: tuple[str, ...]) -> None:
        if state.get(module) == 2:
            return
        assert state.get(module) != 1, "import cycle: " + " -> ".join([*trail, module])
        state[module] = 1
        for target in sorted(graph[module]):
            visit(target, (*trail, module))
        state[module] = 2

    for module in sorted(graph):
        visit(module, ())


# The one function allowed to import the package at run time: the package's own PEP 562
# __getattr__, which imports the module behind a public name (jointbench.fit_center, ...) on first
# access, so that importing one submodule, as every workflow job does, does not load them all. It
# dodges no cycle: the package's modules take nothing from jointbench/__init__.py.
_LAZY_EXPORTS = ("src/jointbench/__init__.py", "__getattr__")


def _imports_the_package(node: ast.AST) -> bool:
    """An import statement of jointbench, or any ``importlib.import_module`` call."""
    if isinstance(node, ast.ImportFrom):
        return (node.module or "").startswith("jointbench")
    if isinstance(node, ast.Import):
        return any(alias.name.startswith("jointbench") for alias in node.names)
    return (
        isinstance(node, ast.Call)
        and isinstance(node.func, ast.Attribute)
        and node.func.attr == "import_module"
    )


def test_no_function_local_imports_of_the_package():
    """Imports of jointbench happen at module level, never inside a function to dodge a cycle."""
    offenders = []
    for path in (ROOT / "src" / "jointbench").rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
                if (str(path.relative_to(ROOT)), node.name) == _LAZY_EXPORTS:
                    continue
                for inner in ast.walk(node):
                    if _imports_the_package(inner):
                        offenders.append(f"{path.relative_to(ROOT)}:{inner.lineno}")
    assert not offenders, offenders


def test_tests_import_their_helpers_as_the_test_command_finds_them():
    """A test module imports a helper module of tests/ by its own name (``from rigs import``):
    pytest puts tests/ on the path, not the repository, so ``from tests.rigs import`` works
    under ``python -m pytest`` from the root (which adds the working directory) and fails
    under the README's ``pytest``."""
    offenders = []
    for path in (ROOT / "tests").rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            names = [node.module or ""] if isinstance(node, ast.ImportFrom) else []
            if isinstance(node, ast.Import):
                names = [alias.name for alias in node.names]
            if any(name == "tests" or name.startswith("tests.") for name in names):
                offenders.append(f"{path.relative_to(ROOT)}:{node.lineno}")
    assert not offenders, offenders


def test_every_file_the_package_holds_besides_its_modules_is_installed_with_it():
    """A file of the package that is not a module (a schema, a paper's values, the limited
    shell of the external estimators' jobs) reaches an install that is not editable only if
    ``pyproject.toml``'s package data names it."""
    package = ROOT / "src" / "jointbench"
    declared = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"][
        "package-data"
    ]["jointbench"]
    tracked = subprocess.run(
        ["git", "ls-files", "-z", "src/jointbench"], cwd=ROOT, capture_output=True, check=True
    ).stdout.decode()
    files = [ROOT / name for name in tracked.split("\0") if name]
    others = [path.relative_to(package) for path in files if path.suffix != ".py"]
    assert others, "no file besides the modules: the listing is wrong"
    missing = [str(path) for path in others if not any(path.match(pattern) for pattern in declared)]
    assert not missing, f"not in [tool.setuptools.package-data]: {missing}"


def test_the_build_backend_required_reads_the_project_table_as_written():
    """An SPDX string as ``license`` (PEP 639) is read by setuptools 77 on; an older one the
    build system admits refuses the whole table, and ``pip install .`` with it fails."""
    pyproject = tomllib.loads((ROOT / "pyproject.toml").read_text())
    (requirement,) = pyproject["build-system"]["requires"]
    name, floor = requirement.split(">=")
    assert name == "setuptools"
    if isinstance(pyproject["project"]["license"], str):
        assert tuple(map(int, floor.split("."))) >= (77,)
