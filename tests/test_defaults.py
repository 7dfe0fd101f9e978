"""Each default is written once, in the configuration (lf3pm.config): every keyword
default of the public API that names a configuration parameter equals it, every CLI
option that sets one takes its default from it, and the robot is the config's."""

import inspect

import pytest
import typer

import lf3pm
import lf3pm.replays as replays
import lf3pm.validation as validation
from lf3pm.cli import app
from lf3pm.config import DEFAULTS
from lf3pm.experiments import correlation, table1
from lf3pm.experiments.benefit.study import StudySettings
from lf3pm.planner import Planner
from lf3pm.replays.ground import smooth_ground
from lf3pm.replays.motion import Motion
from lf3pm.replays.replay_result import ReplayResult, rest_motion
from lf3pm.scenes import build_scene
from lf3pm.solm.occupancy import occupancy_factor
from lf3pm.solm.tiles import make_job
from lf3pm.trajectory import Robot

#: A function's parameter named otherwise than its configuration parameter.
ALIASES = {"sigma_r_deg": "sigma_r"}

#: The public API and, for each function, the sections whose parameters it takes
#: ("" is the top level: the sensor).
API = [
    (lf3pm.load_map, ["map", "scan"]),
    (lf3pm.evaluate, ["", "scan", "metric"]),
    (validation.mde, ["", "scan", "mde"]),
    (validation.mde_along, ["", "scan", "mde"]),
    (replays.replay, ["", "replay", "scan"]),
    (replays.replay_seeds, ["", "replay", "scan"]),
    (replays.replay_bag, ["", "replay", "scan"]),
    (replays.replay_odometry, ["", "replay", "scan", "kiss_icp"]),
    (lf3pm.make_grid, ["solm"]),
    (lf3pm.build_solm, ["solm", "scan", "metric"]),
    (smooth_ground, ["ground"]),
    (make_job, ["scan", "metric", "solm"]),
    (occupancy_factor, ["solm"]),
    (build_scene, ["scene"]),
    (Planner.plan, ["guidance"]),
    (Planner.__init__, ["planner"]),
    (table1.run, ["table1", "mde"]),
    (correlation.run, ["", "correlation"]),
    (StudySettings, ["benefit", "replay"]),  # benefit.run's settings: the sections whole
    (Motion.from_arrays, ["ground"]),
    (Motion.from_csv, ["replay", "ground"]),
    (rest_motion, ["replay"]),
    (ReplayResult.from_run, ["replay"]),
]


def configured(sections, name):
    """(found, value) of parameter ``name`` in the first of ``sections`` that has it."""
    for section in sections:
        owner = DEFAULTS if section == "" else getattr(DEFAULTS, section)
        if name in type(owner).model_fields:
            return True, getattr(owner, name)
    return False, None


def takes_sections(function, sections) -> bool:
    """Whether ``function`` takes its configuration whole: a parameter defaults to the
    defaults (DEFAULTS, a section of it, or None for them)."""
    wholes = [DEFAULTS] + [getattr(DEFAULTS, section) for section in sections if section]
    return any(
        parameter.name in ("config", *sections) and any(parameter.default is whole for whole in [None, *wholes])
        for parameter in inspect.signature(function).parameters.values()
    )


@pytest.mark.parametrize("function, sections", API, ids=lambda f: getattr(f, "__qualname__", ""))
def test_public_defaults_are_the_configuration(function, sections):
    """A parameter named as a configuration parameter defaults to it; where the function
    takes its sections whole (a ``config`` or section parameter defaulting to the
    defaults), such a parameter may default to None instead: an override of the section's."""
    whole = takes_sections(function, sections)
    checked = int(whole)
    for parameter in inspect.signature(function).parameters.values():
        if parameter.default is inspect.Parameter.empty:
            continue
        found, value = configured(sections, ALIASES.get(parameter.name, parameter.name))
        if found:
            checked += 1
            if whole and parameter.default is None:
                continue
            assert parameter.default == value, f"{function.__qualname__}({parameter.name}=...)"
    assert checked, f"{function.__qualname__}: no parameter of {sections} checked"


def test_the_default_robot_is_the_configuration():
    assert Robot().model_dump() == DEFAULTS.robot.model_dump()


def config_names() -> set[str]:
    names = {"sensor"}
    for section in type(DEFAULTS).model_fields:
        owner = getattr(DEFAULTS, section)
        names.update(getattr(type(owner), "model_fields", {}))
    return names


def commands(group, prefix=()):
    for name, command in group.commands.items():
        if hasattr(command, "commands"):
            yield from commands(command, prefix + (name,))
        else:
            yield " ".join(prefix + (name,)), command


def test_cli_options_take_their_defaults_from_the_configuration():
    """An option that sets a configuration parameter has no default of its own (None:
    the configuration's applies, --config FILE.yaml first); its help names that default."""
    names = config_names()
    seen = 0
    for name, command in commands(typer.main.get_command(app)):
        for param in command.params:
            if param.param_type_name == "option" and param.name in names | set(ALIASES):
                seen += 1
                assert param.default is None, f"lf3pm {name} --{param.name.replace('_', '-')}"
    assert seen > 40


#: Parameters named as a configuration parameter that mean something else, with a
#: literal default of their own: (module, function, parameter) and why.
OTHER_MEANINGS = {
    ("experiments/free_poses.py", "random_free_poses", "clearance"): "free-pose sampling keeps 0.5 m, not a pose check",
    ("planner/esdf.py", "traversable", "r_safe"): "0: no clearance beyond the robot radius",
    ("planner/esdf.py", "blocked_reason", "r_safe"): "0: no clearance beyond the robot radius",
    (
        "planner/graph_search.py",
        "search_path",
        "r_safe",
    ): "the bare search: 0, no clearance; Planner passes the robot's",
    ("planner/graph_search.py", "search_path", "weight"): "the bare search's lambda; Planner passes the guidance's",
    ("planner/shortcut.py", "shortcut_path", "weight"): "0: geometry only; Planner passes the guidance's",
    ("scan/scan_simulator.py", "simulate_scan", "noise"): "the simulator's raw sigma: 0 is noise-free",
    ("scan/moving_scan.py", "simulate_moving_scan", "noise"): "the simulator's raw sigma: 0 is noise-free",
    ("replays/lio.py", "run_lio", "threads"): "the odometry's own thread count, not the scan simulator's",
    ("replays/replay_figures.py", "_obstacles", "cell"): "the figure's obstacle raster, not the ground's columns",
}


def literal_defaults():
    """(module, function, parameter, value) of every literal default in lf3pm (config.py aside)
    given to a parameter named as a configuration parameter."""
    import ast
    from pathlib import Path

    names = config_names() | set(ALIASES)
    root = Path(__file__).resolve().parents[1] / "python" / "lf3pm"
    for path in sorted(root.rglob("*.py")):
        if path.name == "config.py":
            continue
        for node in ast.walk(ast.parse(path.read_text())):
            if not isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                continue
            args = node.args
            positional = args.posonlyargs + args.args
            pairs = list(zip(positional[len(positional) - len(args.defaults) :], args.defaults))
            pairs += [(a, d) for a, d in zip(args.kwonlyargs, args.kw_defaults) if d is not None]
            for arg, default in pairs:
                if arg.arg in names and isinstance(default, ast.Constant) and default.value is not None:
                    yield path.relative_to(root).as_posix(), node.name, arg.arg, default.value


def test_no_configuration_default_is_written_twice():
    """No function writes a configuration parameter's default as a literal of its own:
    it reads lf3pm.config.DEFAULTS (or the parameter means something else, listed above)."""
    found = [
        f"{module}: {function}({name}={value!r})"
        for module, function, name, value in literal_defaults()
        if (module, function, name) not in OTHER_MEANINGS
    ]
    assert not found, "defaults written outside lf3pm.config: " + "; ".join(found)


def test_cli_help_is_written_once_in_the_configuration():
    """An option's help is its parameter's description (lf3pm.config); a command passes a
    text of its own only where the parameter means more there, never a copy of it."""
    import ast
    from pathlib import Path

    copies = []
    for path in sorted((Path(__file__).resolve().parents[1] / "python" / "lf3pm" / "cli").glob("*.py")):
        for node in ast.walk(ast.parse(path.read_text())):
            if not (isinstance(node, ast.Call) and getattr(node.func, "id", None) == "option" and node.args):
                continue
            texts = [k.value for k in node.keywords if k.arg == "help"]
            if not (texts and isinstance(texts[0], ast.Constant) and isinstance(node.args[0], ast.Constant)):
                continue
            section, _, name = node.args[0].value.rpartition(".")
            owner = getattr(DEFAULTS, section) if section else DEFAULTS
            if texts[0].value.strip() == type(owner).model_fields[name].description.strip():
                copies.append(f"{path.name}:{node.lineno} {node.args[0].value}")
    assert not copies, "help copied from the configuration: " + ", ".join(copies)


def test_each_odometry_s_settings_are_its_section_s_defaults():
    """The configuration's replay.odometries gives none by default; what `lf3pm config`
    shows for each registered odometry (registry.with_settings) is its settings section's
    defaults, and such a configuration runs and records as the defaults do (no setting
    changed)."""
    from lf3pm.replays import registry

    assert DEFAULTS.replay.odometries == {}
    shown = registry.with_settings(DEFAULTS).replay.odometries
    assert list(shown) == list(registry.odometries())
    for name, adapter in registry.odometries().items():
        assert shown[name] == adapter.Settings().model_dump(mode="json"), name
        assert registry.changed_settings(name, shown[name]) == {}


def test_the_rest_limits_are_the_replay_section_s():
    """rest_motion judges a rest by the replay section's rest_window and rest_speed_limit."""
    import numpy as np

    times = np.arange(0.0, 2.05, 0.1)
    truth = np.repeat(np.eye(4)[None], len(times), axis=0)
    poses = truth.copy()
    poses[:, 0, 3] = 0.03 * times  # 0.03 m/s
    assert rest_motion(times, truth, poses)["steady"]
    strict = DEFAULTS.replay.model_copy(update={"rest_speed_limit": 0.02})
    assert not rest_motion(times, truth, poses, strict)["steady"]
