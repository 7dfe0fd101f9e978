"""bench/ holds benchmarks only, each run by `make bench`, from a fresh clone: read from the
sources (AST and text), nothing is run.

A benchmark is a bench/*.py script (it has an ``if __name__ == "__main__":`` block); the
other modules there are helpers the benchmarks import. Every benchmark is in the Makefile's
bench target; no bench module imports a private lf3pm name (the bound core, lf3pm._core, is
the C++ API and allowed), puts tests/ on sys.path or imports a tests/ module, or reads a run
folder under out/; every lf3pm name a bench module imports exists."""

from __future__ import annotations

import ast
import importlib
import importlib.util
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
BENCH = ROOT / "bench"
MODULES = sorted(BENCH.glob("*.py"))


def tree(path: Path) -> ast.Module:
    return ast.parse(path.read_text(), filename=str(path))


def is_script(module: ast.Module) -> bool:
    """Whether the module has a top-level ``if __name__ == "__main__":`` block."""
    for node in module.body:
        if isinstance(node, ast.If) and isinstance(node.test, ast.Compare):
            left, right = node.test.left, node.test.comparators
            if isinstance(left, ast.Name) and left.id == "__name__" and right:
                if isinstance(right[0], ast.Constant) and right[0].value == "__main__":
                    return True
    return False


def bench_recipe() -> str:
    """The recipe lines of the Makefile's bench target."""
    lines = (ROOT / "Makefile").read_text().splitlines()
    start = next(i for i, line in enumerate(lines) if line.startswith("bench:"))
    recipe = []
    for line in lines[start + 1 :]:
        if not line.startswith("\t"):
            break
        recipe.append(line)
    return "\n".join(recipe)


def private_lf3pm_imports(module: ast.Module) -> list[str]:
    """``lf3pm`` names starting with an underscore that ``module`` imports or reads, other than
    the bound core ``lf3pm._core``."""

    def private(dotted: str) -> bool:
        parts = dotted.split(".")
        if parts[0] != "lf3pm":
            return False
        if len(parts) > 1 and parts[1] == "_core":
            return False
        return any(part.startswith("_") for part in parts[1:])

    found = []
    for node in ast.walk(module):
        if isinstance(node, ast.Import):
            found += [a.name for a in node.names if private(a.name)]
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            if private(node.module):
                found.append(node.module)
            elif node.module.split(".")[0] == "lf3pm":
                found += [f"{node.module}.{a.name}" for a in node.names if private(f"{node.module}.{a.name}")]
        elif isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name) and node.value.id == "lf3pm":
            if private(f"lf3pm.{node.attr}"):
                found.append(f"lf3pm.{node.attr}")
    return found


def docstrings(module: ast.Module) -> set[int]:
    """ids of the docstring constants of the module, its classes and functions."""
    found = set()
    for node in ast.walk(module):
        if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef)) and node.body:
            first = node.body[0]
            if isinstance(first, ast.Expr) and isinstance(first.value, ast.Constant):
                found.add(id(first.value))
    return found


def test_bench_has_benchmarks():
    assert sum(is_script(tree(p)) for p in MODULES) >= 10


@pytest.mark.parametrize("path", [p for p in MODULES if is_script(tree(p))], ids=lambda p: p.name)
def test_every_benchmark_is_run_by_make_bench(path):
    assert f"bench/{path.name}" in bench_recipe(), f"{path.name} is not in the Makefile's bench target"


@pytest.mark.parametrize("path", MODULES, ids=lambda p: p.name)
def test_bench_imports_no_private_lf3pm_name(path):
    assert private_lf3pm_imports(tree(path)) == []


@pytest.mark.parametrize("path", MODULES, ids=lambda p: p.name)
def test_bench_does_not_import_tests(path):
    module = tree(path)
    assert "sys.path" not in path.read_text(), f"{path.name} changes sys.path"
    test_modules = {p.stem for p in (ROOT / "tests").glob("*.py")}
    imported = set()
    for node in ast.walk(module):
        if isinstance(node, ast.Import):
            imported |= {a.name.split(".")[0] for a in node.names}
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            imported.add(node.module.split(".")[0])
    assert not imported & (test_modules | {"tests"}), sorted(imported & (test_modules | {"tests"}))


@pytest.mark.parametrize("path", MODULES, ids=lambda p: p.name)
def test_bench_reads_no_run_folder(path):
    module = tree(path)
    skip = docstrings(module)
    strings = [
        node.value
        for node in ast.walk(module)
        if isinstance(node, ast.Constant) and isinstance(node.value, str) and id(node) not in skip
    ]
    assert [s for s in strings if re.match(r"\.?/?out(/|$)", s)] == []


def module_exists(dotted: str) -> bool:
    try:
        return importlib.util.find_spec(dotted) is not None
    except ModuleNotFoundError:  # a parent is a module, not a package
        return False


@pytest.mark.parametrize("path", MODULES, ids=lambda p: p.name)
def test_bench_imports_resolve(path):
    """Every ``from lf3pm... import name`` of a bench module, at its top or inside a function,
    names something lf3pm has: a refactor that renames it must update the benchmark."""
    missing = []
    for node in ast.walk(tree(path)):
        if isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            if node.module.split(".")[0] != "lf3pm":
                continue
            module = importlib.import_module(node.module)
            for alias in node.names:
                if not hasattr(module, alias.name) and not module_exists(f"{node.module}.{alias.name}"):
                    missing.append(f"{node.module}.{alias.name}")
        elif isinstance(node, ast.Import):
            for alias in node.names:
                if alias.name.split(".")[0] == "lf3pm" and not module_exists(alias.name):
                    missing.append(alias.name)
    assert missing == [], f"{path.name} imports names lf3pm does not have"


def test_the_checks_see_what_they_look_for():
    bad = ast.parse(
        "import sys\nfrom lf3pm.replays._lio_worker import GenZ\nfrom lf3pm.replays.lio import _imu_rows\n"
        "from lf3pm import _core\nimport lf3pm\nlf3pm._private()\n"
    )
    assert private_lf3pm_imports(bad) == ["lf3pm.replays._lio_worker", "lf3pm.replays.lio._imu_rows", "lf3pm._private"]
    assert is_script(ast.parse('if __name__ == "__main__":\n    pass\n'))
    assert not is_script(ast.parse("x = 1\n"))
