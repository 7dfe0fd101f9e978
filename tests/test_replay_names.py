"""No replay method or odometry name is compared as a string outside the registries
(lf3pm.replays.methods.METHODS, lf3pm.replays.registry) and the YAML/CLI boundary
(lf3pm.config, lf3pm.cli): code asks a method or an odometry what it is instead."""

import ast
from pathlib import Path

from lf3pm.replays import registry
from lf3pm.replays.methods import METHODS

PACKAGE = Path(__file__).resolve().parents[1] / "python" / "lf3pm"
#: Where the names may stand: the registries and the YAML/CLI boundary.
BOUNDARY = ("config.py", "cli/", "replays/registry.py", "replays/methods.py")
#: The same strings meaning something else, or a use its owner is yet to move onto the
#: registry: (module, string) and why.
OTHER_MEANINGS = {
    ("solm/cluster.py", "auto"): "Ray's address of a running cluster, not an odometry",
    ("experiments/benefit/protocol.py", "odometry"): "the replay section's field of that name, not the KISS-ICP method",
}


def compared_strings(path: Path):
    """(line, string) of each string constant compared (==, !=, in, not in) in ``path``."""
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if not isinstance(node, ast.Compare):
            continue
        for part in (node.left, *node.comparators):
            elements = part.elts if isinstance(part, (ast.Tuple, ast.List, ast.Set)) else [part]
            for element in elements:
                if isinstance(element, ast.Constant) and isinstance(element.value, str):
                    yield node.lineno, element.value


def test_no_method_or_odometry_name_is_compared_as_a_string():
    names = set(METHODS) | set(registry.odometries()) | {registry.AUTO}
    found = []
    for path in sorted(PACKAGE.rglob("*.py")):
        module = path.relative_to(PACKAGE).as_posix()
        if module.startswith(BOUNDARY):
            continue
        found += [
            f"{module}:{line} compares {value!r}"
            for line, value in compared_strings(path)
            if value in names and (module, value) not in OTHER_MEANINGS
        ]
    assert not found, "; ".join(found)


def test_the_config_names_the_registered_methods():
    """config.py names the methods (REPLAY_METHODS) but no odometry: its odometry fields
    (replay.odometry, benefit.odometry) and replay.odometries' keys are checked against
    the registry (registry.check_name, registry.settings), which a plugin extends."""
    import lf3pm.config as config
    from lf3pm.config import DEFAULTS, REPLAY_METHODS

    assert tuple(METHODS) == REPLAY_METHODS
    assert not hasattr(config, "LIO_ODOMETRIES")
    assert DEFAULTS.replay.odometry == DEFAULTS.benefit.odometry == registry.AUTO


def test_the_checker_finds_a_comparison(tmp_path):
    path = tmp_path / "m.py"
    path.write_text('if method == "lio" or odometry in ("genz", "dlio"):\n    pass\n')
    assert list(compared_strings(path)) == [(1, "lio"), (1, "genz"), (1, "dlio")]
