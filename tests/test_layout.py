"""The package's layout: no import cycle between lf3pm's packages and top-level
modules, lazy (in-function) imports included."""

import ast
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[1] / "python" / "lf3pm"


def unit(module: str) -> str:
    """The unit a module belongs to: lf3pm.<package> for a subpackage's modules,
    the module itself at the top level."""
    parts = module.split(".")
    return ".".join(parts[:2])


def module_name(path: Path) -> str:
    parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def imports(path: Path) -> set[str]:
    """Every lf3pm module ``path`` imports, at its top or inside a function."""
    name = module_name(path)
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    found = set()
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            found.update(alias.name for alias in node.names if alias.name.startswith("lf3pm"))
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")[: len(package.split(".")) - node.level + 1]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            if target.startswith("lf3pm"):
                found.add(target)
                found.update(f"{target}.{alias.name}" for alias in node.names)
    return found


def unit_graph() -> dict[str, set[str]]:
    """Unit -> the units it imports (the top-level facade lf3pm/__init__.py and the
    CLI entry points, which nothing inside imports, left out)."""
    graph: dict[str, set[str]] = {}
    modules = {module_name(p) for p in PACKAGE.rglob("*.py")}
    for path in PACKAGE.rglob("*.py"):
        source = module_name(path)
        if source in ("lf3pm", "lf3pm.__main__"):
            continue
        for target in imports(path):
            while target not in modules and "." in target:  # `from pkg import name`: the module holding it
                target = target.rpartition(".")[0]
            if target in ("lf3pm",) or unit(target) == unit(source):
                continue
            graph.setdefault(unit(source), set()).add(unit(target))
    return graph


def cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components of more than one unit (Tarjan)."""
    index, low, stack, on_stack, found = {}, {}, [], set(), []

    def visit(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in graph.get(v, ()):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                found.append(sorted(component))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return found


def test_the_cycle_finder_finds_a_cycle():
    assert cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]
    assert cycles({"a": {"b"}, "b": set()}) == []


def test_no_import_cycle_between_packages():
    found = cycles(unit_graph())
    assert not found, "import cycles between lf3pm's packages: " + "; ".join(" <-> ".join(c) for c in found)


def test_the_cli_is_thin():
    """Each command module stays a few lines over the library."""
    for path in (PACKAGE / "cli").glob("*.py"):
        lines = len(path.read_text().splitlines())
        assert lines <= 250, f"{path.name}: {lines} lines"


def test_the_readme_layout_names_every_package_and_module():
    """README's layout row for python/lf3pm/ names each subpackage (as `name/`) and each
    public top-level module (as `name`)."""
    readme = (PACKAGE.parents[1] / "README.md").read_text()
    row = next(line for line in readme.splitlines() if line.startswith("| `python/lf3pm/`"))
    for entry in sorted(PACKAGE.iterdir()):
        if entry.name.startswith(("_", ".")) or entry.name == "py.typed":
            continue
        if entry.is_dir() and entry.name != "__pycache__":
            assert f"`{entry.name}/`" in row, entry.name
        elif entry.suffix == ".py":
            assert f"`{entry.stem}`" in row, entry.stem
