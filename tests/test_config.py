"""The typed configuration (lf3pm.config): defaults read from the C++ structs, every
value validated once, --config files overridden by flags, one-line errors."""

import json
from pathlib import Path

import numpy as np
import pytest
import yaml
from typer.testing import CliRunner

import lf3pm
from lf3pm import _core
from lf3pm.cli import app
from lf3pm.config import DEFAULTS, ConfigError, MapConfig, MetricConfig, ScanConfig, load_config, to_yaml
from lf3pm.scenes import build_scene

CONFIG_DIR = Path(__file__).resolve().parents[1] / "config"


@pytest.fixture(scope="module")
def boxes(tmp_path_factory):
    path = tmp_path_factory.mktemp("config") / "boxes.npy"
    np.save(path, build_scene("boxes").points)
    return str(path)


def one_error_line(done):
    lines = [line for line in done.output.splitlines() if line.strip()]
    assert done.exit_code == 2 and len(lines) == 1 and lines[0].startswith("lf3pm: error:"), done.output
    return lines[0]


def test_defaults_are_the_cores():
    core_map, core_scan, core_eval = _core.MapParams(), _core.ScanParams(), _core.EvalParams()
    assert MapConfig().knn == core_map.knn and MapConfig().plane_threshold == core_map.plane_threshold
    assert MapConfig().max_neighbor_distance == core_map.max_neighbor_distance
    assert ScanConfig().seed == core_scan.seed and ScanConfig().threads == core_scan.threads
    assert ScanConfig().scan_voxel == core_scan.scan_voxel
    assert MetricConfig().dof == core_eval.dof and MetricConfig().w1 == core_eval.weights.w1
    assert MetricConfig().association == core_eval.association.name
    limits = _core.RobotLimits()
    for name in ("vmax_lon", "vmax_lat", "wmax", "amax_lon", "amax_lat", "alpha_max", "r_safe"):
        assert getattr(DEFAULTS.robot, name) == getattr(limits, name), name


def test_sections_build_the_core_structs():
    sensor = lf3pm.get_sensor("mid70")
    scan = ScanConfig(seed=7, scan_voxel=0.2).core(sensor, stream=3)
    assert (scan.min_range, scan.max_range) == (sensor.min_range, sensor.max_range)
    assert scan.noise_sigma == sensor.range_noise_sigma and (scan.seed, scan.stream) == (7, 3)
    params = MetricConfig(dof=3, association="surfel", w1=0.25).core(scan, ray_weight=2.0)
    assert (params.dof, params.association, params.ray_weight) == (3, _core.Association.surfel, 2.0)
    assert params.weights.w2 == pytest.approx(0.75) and params.scan.seed == 7


def test_the_shipped_default_config_is_current():
    # config/default.yaml is what `lf3pm config` prints (every registered odometry's
    # settings in replay.odometries: registry.with_settings), and reads back to the defaults.
    from lf3pm.replays import registry

    text = (CONFIG_DIR / "default.yaml").read_text()
    body = "".join(line + "\n" for line in text.splitlines() if not line.startswith("#"))
    assert body == to_yaml(registry.with_settings(DEFAULTS))
    loaded = load_config(CONFIG_DIR / "default.yaml")
    assert registry.with_settings(loaded) == registry.with_settings(DEFAULTS)
    assert loaded.model_copy(update={"replay": DEFAULTS.replay}) == DEFAULTS
    assert all(registry.changed_settings(name, given) == {} for name, given in loaded.replay.odometries.items())
    done = CliRunner().invoke(app, ["config"])
    assert done.exit_code == 0 and done.output == body


#: The example --config files: not the benefit study's cases and protocol files (benefit_*.yaml,
#: their own schemas: tests/test_benefit_cases.py, tests/test_benefit_protocol.py).
EXAMPLES = sorted(p for p in CONFIG_DIR.glob("*.yaml") if not p.name.startswith("benefit_"))


@pytest.mark.parametrize("path", EXAMPLES, ids=lambda p: p.name)
def test_every_example_config_loads(path):
    """Each example loads, every value it writes arrives in the configuration, and
    everything it leaves out keeps its default."""
    config = load_config(path)
    lf3pm.get_sensor(config.sensor)
    written = yaml.safe_load(path.read_text())
    loaded = yaml.safe_load(to_yaml(config))
    defaults = yaml.safe_load(to_yaml(DEFAULTS))
    for key, value in loaded.items():
        if isinstance(value, dict):
            for name, setting in value.items():
                expected = written.get(key, {}).get(name, defaults[key][name])
                assert setting == expected, f"{path.name}: {key}.{name}"
        else:
            assert value == written.get(key, defaults[key]), f"{path.name}: {key}"


def test_a_file_sets_what_no_flag_gives_and_flags_override_it(boxes, tmp_path):
    config = tmp_path / "c.yaml"
    config.write_text(yaml.safe_dump({"scan": {"noise": 0.0, "seed": 3}, "metric": {"w1": 0.3}}))
    run = ["evaluate", boxes, "--pose", "0", "0", "0.5", "0", "--json", "--config", str(config)]
    from_file = json.loads(CliRunner().invoke(app, run).output)
    assert from_file["params"]["seed"] == 3 and from_file["params"]["noise"] == 0.0
    assert from_file["params"]["w1"] == 0.3
    flagged = json.loads(CliRunner().invoke(app, run + ["--seed", "5"]).output)
    assert flagged["params"]["seed"] == 5 and flagged["params"]["w1"] == 0.3
    api = lf3pm.evaluate(boxes, (0, 0, 0.5, 0), seed=3, noise=0.0, w1=0.3)
    assert api.q_n == from_file["q_n"]


def test_robot_and_guidance_from_a_file():
    config = load_config(CONFIG_DIR / "car_vlp16.yaml", {"robot.vmax_lon": 1.5})
    assert config.robot.kind == "car" and config.robot.min_turn_radius == 2.5 and config.robot.vmax_lon == 1.5
    assert config.robot.vmax_norm is None  # a car has no speed-norm limit
    omni = load_config(None, {"robot.vmax_lon": 2.0})
    assert omni.robot.vmax_norm == 2.0  # derived from the new limit, not the default's 1


@pytest.mark.parametrize(
    "content, message",
    [
        ("scan: {noise: .inf}\n", "c.yaml: scan.noise must be finite"),
        ("scan: {seed: -1}\n", "c.yaml: scan.seed must be greater than or equal to 0, got -1"),
        ("scan: {bogus: 1}\n", "c.yaml: scan.bogus is not a parameter lf3pm knows"),
        ("bogus: {a: 1}\n", "c.yaml: bogus is not a parameter lf3pm knows"),
        ("solm: {space: r4}\n", "c.yaml: solm.space must be 'r2', 'se2', 'r3' or 'r3yaw', got 'r4'"),
        ("metric: {dof: 2.5}\n", "c.yaml: metric.dof must be 3 or 6"),
        ("robot: {vmax_lon: 0}\n", "c.yaml: robot.vmax_lon must be greater than or equal to 0.001"),
        ("robot: {wheels: 4}\n", "c.yaml: robot.wheels is not a parameter lf3pm knows"),
        ("- a\n- b\n", "c.yaml: a config is a mapping of sections, got list"),
        ("scan: [1, 2\n", "c.yaml: not YAML"),
    ],
)
def test_a_bad_config_file_is_one_line_naming_it(boxes, tmp_path, content, message):
    config = tmp_path / "c.yaml"
    config.write_text(content)
    done = CliRunner().invoke(app, ["evaluate", boxes, "--pose", "0", "0", "0.5", "0", "--config", str(config)])
    assert message in one_error_line(done)


def test_a_missing_config_file_is_one_line(boxes, tmp_path):
    done = CliRunner().invoke(
        app, ["solm", "build", boxes, "-o", str(tmp_path / "s.zarr"), "--config", str(tmp_path / "none.yaml")]
    )
    assert "none.yaml: cannot read the config" in one_error_line(done)
    assert not (tmp_path / "s.zarr").exists()


def test_the_library_validates_through_the_same_sections(boxes):
    world = lf3pm.load_map(boxes)
    with pytest.raises(ConfigError, match="scan.noise must be finite"):
        lf3pm.evaluate(world, (0, 0, 0.5, 0), noise=float("inf"))
    with pytest.raises(ConfigError, match="metric.association must be 'knn' or 'surfel'"):
        lf3pm.evaluate(world, (0, 0, 0.5, 0), association="nearest")
    with pytest.raises(ConfigError, match="map.knn must be greater than or equal to 3"):
        lf3pm.load_map(boxes, knn=1)
    with pytest.raises(ConfigError, match="solm.res must be greater than 0"):
        lf3pm.make_grid(world, "r2", 0.0)
    with pytest.raises(ConfigError, match="mde.trials must be greater than or equal to 1"):
        from lf3pm.validation import mde

        mde(world, (0, 0, 0.5, 0), trials=0)
