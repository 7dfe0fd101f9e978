"""The package's layout: no import cycle in lf3pm, lazy (in-function) imports
included: neither between its packages and top-level modules, nor between modules
(inside one package as well as across packages)."""

import ast
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[1] / "python" / "lf3pm"


def unit(module: str) -> str:
    """The unit a module belongs to: lf3pm.<package> for a subpackage's modules,
    the module itself at the top level."""
    parts = module.split(".")
    return ".".join(parts[:2])


def module_name(path: Path, package: Path = PACKAGE) -> str:
    parts = path.relative_to(package.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def imports(path: Path, package_root: Path = PACKAGE) -> set[str]:
    """Every lf3pm module ``path`` imports, at its top or inside a function."""
    name = module_name(path, package_root)
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


def ancestors(module: str) -> set[str]:
    """The packages that hold ``module`` (lf3pm.a.b: lf3pm, lf3pm.a)."""
    parts = module.split(".")
    return {".".join(parts[:k]) for k in range(1, len(parts))}


def module_graph(package: Path = PACKAGE) -> dict[str, set[str]]:
    """Module -> the lf3pm modules it imports, lazy imports included (the facade and
    entry points left out, as in unit_graph). Importing ``a.b.c`` from outside package
    ``a.b`` runs ``a/b/__init__.py`` first: an edge to it too (a package's own modules
    are loaded from inside it, so it is no edge of theirs)."""
    graph: dict[str, set[str]] = {}
    modules = {module_name(p, package) for p in package.rglob("*.py")}
    for path in package.rglob("*.py"):
        source = module_name(path, package)
        if source in ("lf3pm", "lf3pm.__main__"):
            continue
        inside = ancestors(source) | {source}
        for target in imports(path, package):
            while target not in modules and "." in target:
                target = target.rpartition(".")[0]
            for module in (ancestors(target) | {target}) - inside - {"lf3pm"}:
                graph.setdefault(source, set()).add(module)
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


def test_the_module_graph_finds_cycles_inside_a_package_and_through_an_init(tmp_path):
    """A lazy import back inside one package is a cycle; so is a package whose __init__
    imports a module that imports the package's modules from outside it; a package's
    __init__ importing its own modules, which import each other one way, is none."""
    root = tmp_path / "lf3pm"
    files = {
        "__init__.py": "",
        "p/__init__.py": "from lf3pm.p.a import A\n",
        "p/a.py": "from lf3pm.p import b\nA = 1\n",
        "p/b.py": "def f():\n    from .a import A\n    return A\n",
        "q/__init__.py": "def run():\n    from lf3pm.q.study import run\n",
        "q/study.py": "from lf3pm.fit import fit\n",
        "q/records.py": "",
        "fit.py": "from lf3pm.q.records import Pair\n",
        "r/__init__.py": "from lf3pm.r.x import X\n",
        "r/x.py": "from lf3pm.r.y import Y\nX = 1\n",
        "r/y.py": "Y = 1\n",
    }
    for name, text in files.items():
        (root / name).parent.mkdir(parents=True, exist_ok=True)
        (root / name).write_text(text)
    assert cycles(module_graph(root)) == [["lf3pm.fit", "lf3pm.q", "lf3pm.q.study"], ["lf3pm.p.a", "lf3pm.p.b"]]


def test_the_module_graph_sees_imports_inside_a_package_and_through_its_init():
    graph = module_graph()
    assert "lf3pm.experiments.benefit.records" in graph["lf3pm.experiments.benefit.report"]
    # The study imports its records from inside their package: no edge to its __init__;
    # its figures import lf3pm.solm.figures from outside lf3pm.solm: an edge to its __init__.
    assert "lf3pm.experiments.benefit" not in graph["lf3pm.experiments.benefit.study"]
    assert {"lf3pm.solm", "lf3pm.solm.figures"} <= graph["lf3pm.experiments.benefit.figures"]


def test_no_import_cycle_between_modules():
    """Inside a package too: benefit's report and figures import its records, never back."""
    found = cycles(module_graph())
    assert not found, "import cycles between lf3pm's modules: " + "; ".join(" <-> ".join(c) for c in found)


def test_the_benefit_report_and_figures_read_its_records_only():
    """Of the experiments, the benefit study's report and figures import its records alone
    (not how the study runs or computes)."""
    graph = module_graph()
    for name in ("report", "figures"):
        used = {m for m in graph[f"lf3pm.experiments.benefit.{name}"] if m.startswith("lf3pm.experiments")}
        assert used == {"lf3pm.experiments.benefit.records"}, (name, used)


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
