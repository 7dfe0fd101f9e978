"""Tests of lf3pm.sensors: presets, patterns, YAML sensors and their errors."""

from __future__ import annotations

import hashlib
import math
from pathlib import Path

import numpy as np
import pytest

from lf3pm.errors import Lf3pmError, SensorError
from lf3pm.sensors import Sensor, get_sensor, list_sensors, load_sensor_yaml

PATTERN_DIR = Path(__file__).resolve().parents[1] / "python" / "lf3pm" / "sensors" / "patterns"

EXPECTED_RAYS = {
    "vlp16": 16 * 1800,  # 28,800
    "hdl32": 32 * 2170,  # 69,440
    "os1-64": 64 * 1024,  # 65,536
    "mid40": 10_000,  # 100,000 pts/s x 0.1 s
    "mid70": 10_000,
    "mid360": 20_000,  # 200,000 pts/s x 0.1 s
    "avia": 24_000,  # 240,000 pts/s x 0.1 s
}

SPINNING = {
    # name: (elevations in degrees as on the datasheet, azimuth count, datasheet rounding)
    "vlp16": ([-15, -13, -11, -9, -7, -5, -3, -1, 1, 3, 5, 7, 9, 11, 13, 15], 1800, 1e-9),
    "hdl32": (
        [
            -30.67,
            -29.33,
            -28.00,
            -26.67,
            -25.33,
            -24.00,
            -22.67,
            -21.33,
            -20.00,
            -18.67,
            -17.33,
            -16.00,
            -14.67,
            -13.33,
            -12.00,
            -10.67,
            -9.33,
            -8.00,
            -6.67,
            -5.33,
            -4.00,
            -2.67,
            -1.33,
            0.00,
            1.33,
            2.67,
            4.00,
            5.33,
            6.67,
            8.00,
            9.33,
            10.67,
        ],
        2170,
        0.006,
    ),
    "os1-64": (list(np.linspace(-22.5, 22.5, 64)), 1024, 1e-9),
}


def angles_deg(sensor: Sensor):
    d = sensor.directions
    return np.degrees(np.arctan2(d[:, 1], d[:, 0])), np.degrees(np.arcsin(np.clip(d[:, 2], -1, 1)))


# ---------------------------------------------------------------- presets


def test_list_sensors_order_and_names():
    names = [s.name for s in list_sensors()]
    assert names == ["vlp16", "hdl32", "os1-64", "mid40", "mid70", "mid360", "avia"]
    assert names == [s.name for s in list_sensors()]  # stable


@pytest.mark.parametrize("name", sorted(EXPECTED_RAYS))
def test_ray_counts(name):
    sensor = get_sensor(name)
    assert sensor.num_rays == EXPECTED_RAYS[name]
    assert sensor.directions.shape == (EXPECTED_RAYS[name], 3)


@pytest.mark.parametrize("sensor", list_sensors(), ids=lambda s: s.name)
def test_directions_unit_float64_contiguous(sensor):
    d = sensor.directions
    assert d.dtype == np.float64
    assert d.flags["C_CONTIGUOUS"]
    assert np.isfinite(d).all()
    np.testing.assert_allclose(np.linalg.norm(d, axis=1), 1.0, atol=1e-12)


@pytest.mark.parametrize("sensor", list_sensors(), ids=lambda s: s.name)
def test_fields_sane(sensor):
    assert 0 < sensor.min_range < sensor.max_range
    assert sensor.range_noise_sigma >= 0
    assert 0 < sensor.horizontal_fov <= 2 * math.pi + 1e-12
    assert sensor.description and sensor.source
    assert isinstance(sensor.approximate, bool)


def test_preset_figures():
    s = {x.name: x for x in list_sensors()}
    figures = {  # name: (min, max, sigma, horizontal fov deg, approximate)
        "vlp16": (0.5, 100.0, 0.015, 360.0, False),
        "hdl32": (1.0, 100.0, 0.01, 360.0, False),
        "os1-64": (0.3, 120.0, 0.015, 360.0, False),
        "mid40": (0.1, 130.0, 0.02, 38.4, False),
        "mid70": (0.05, 130.0, 0.02, 70.4, False),
        "mid360": (0.1, 70.0, 0.02, 360.0, True),
        "avia": (1.0, 190.0, 0.02, 70.4, True),
    }
    for name, (lo, hi, sigma, fov, approx) in figures.items():
        assert s[name].min_range == lo, name
        assert s[name].max_range == hi, name
        assert s[name].range_noise_sigma == sigma, name
        assert math.degrees(s[name].horizontal_fov) == pytest.approx(fov), name
        assert s[name].approximate is approx, name
    assert "approximat" in s["mid360"].description.lower()
    assert "approximat" in s["avia"].description.lower()


@pytest.mark.parametrize("name", sorted(SPINNING))
def test_spinning_elevations_match_datasheet(name):
    expected, columns, tol = SPINNING[name]
    sensor = get_sensor(name)
    _, el = angles_deg(sensor)
    beams = len(expected)
    # Column by column: every column holds the same elevations, bottom to top.
    el = el.reshape(columns, beams)
    np.testing.assert_allclose(el, np.broadcast_to(el[0], el.shape), atol=1e-9)
    np.testing.assert_allclose(np.sort(el[0]), np.sort(expected), atol=tol)
    assert np.all(np.diff(el[0]) > 0)


@pytest.mark.parametrize("name", sorted(SPINNING))
def test_spinning_azimuth_order(name):
    expected, columns, _ = SPINNING[name]
    sensor = get_sensor(name)
    d = sensor.directions.reshape(columns, len(expected), 3)
    az = np.mod(np.arctan2(d[:, :, 1], d[:, :, 0]), 2 * math.pi)
    az[0] = 0.0  # exactly zero, avoid 2*pi wrap of -0.0
    # all beams of a column share an azimuth; columns go 0 .. 2*pi exclusive in equal steps
    np.testing.assert_allclose(az, np.broadcast_to(az[:, :1], az.shape), atol=1e-9)
    np.testing.assert_allclose(az[:, 0], 2 * math.pi * np.arange(columns) / columns, atol=1e-9)


def test_vlp16_first_column_points_forward():
    d = get_sensor("vlp16").directions
    assert np.allclose(d[:16, 1], 0.0)
    assert np.all(d[:16, 0] > 0)
    assert d[0, 2] == pytest.approx(math.sin(math.radians(-15)))


# ---------------------------------------------------------------- Livox patterns


def test_pattern_files_bundled_byte_for_byte():
    sha = {
        "mid40.npy": "87e0b43474689af940943d4daa8e026175349f7149ee85d56795b54c1a2c1973",
        "mid70.npy": "fed2a4eda89bd74173b7ba4c3eb8f001bb55394cdc3945e02b3880b436f4150e",
    }
    for fname, digest in sha.items():
        assert hashlib.sha256((PATTERN_DIR / fname).read_bytes()).hexdigest() == digest
    assert (PATTERN_DIR / "LICENSE-MuJoCo-LiDAR").read_text().startswith("MIT License")
    assert "22c082640ed0f8c244c23ec284691300389be836" in (PATTERN_DIR / "README.md").read_text()


def test_mid70_cone_and_counts():
    s = get_sensor("mid70")
    assert s.num_rays == 10_000
    off_axis = np.degrees(np.arccos(np.clip(s.directions[:, 0], -1, 1)))
    assert off_axis.max() < 35.3
    assert off_axis.max() > 30.0  # it does fill the field of view
    assert get_sensor("mid70", integration_time=0.2).num_rays == 20_000
    assert get_sensor("mid70", integration_time=0.05).num_rays == 5_000


def test_mid70_matches_pattern_file_in_order():
    raw = np.load(PATTERN_DIR / "mid70.npy").astype(np.float64)
    s = get_sensor("mid70", integration_time=0.2)
    az, el = raw[:20_000, 0], raw[:20_000, 1]
    expected = np.stack([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)], axis=1)
    np.testing.assert_allclose(s.directions, expected, atol=1e-12)
    # longer integration = same prefix plus more rays
    np.testing.assert_array_equal(get_sensor("mid70").directions, s.directions[:10_000])


def test_pattern_ring_buffer():
    s = get_sensor("mid70", integration_time=4.5)  # 450,000 rays > 400,000 in the file
    assert s.num_rays == 450_000
    np.testing.assert_array_equal(s.directions[400_000:], s.directions[:50_000])


def test_mid40_cone():
    s = get_sensor("mid40")
    assert s.num_rays == 10_000
    off_axis = np.degrees(np.arccos(np.clip(s.directions[:, 0], -1, 1)))
    assert off_axis.max() < 19.3


def test_mid360_band_and_coverage():
    s = get_sensor("mid360")
    az, el = angles_deg(s)
    assert el.min() >= -7.0 - 1e-9 and el.max() <= 52.0 + 1e-9
    assert el.min() < -6.5 and el.max() > 51.5
    for quadrant in range(4):
        lo, hi = -180 + 90 * quadrant, -90 + 90 * quadrant
        assert np.count_nonzero((az >= lo) & (az < hi)) > 0.2 * s.num_rays
    assert get_sensor("mid360", integration_time=0.2).num_rays == 40_000


def test_mid360_uniform_in_solid_angle():
    s = get_sensor("mid360")
    z = s.directions[:, 2]
    zlo, zhi = math.sin(math.radians(-7)), math.sin(math.radians(52))
    hist, _ = np.histogram(z, bins=10, range=(zlo, zhi))
    assert hist.min() > 0.9 * s.num_rays / 10 and hist.max() < 1.1 * s.num_rays / 10


def test_mid360_non_repetitive_prefix():
    a = get_sensor("mid360").directions
    b = get_sensor("mid360", integration_time=0.3).directions
    np.testing.assert_array_equal(b[: len(a)], a)
    # no repeated rays
    assert len(np.unique(np.round(b, 12), axis=0)) == len(b)


def test_avia_field_of_view():
    s = get_sensor("avia")
    az, el = angles_deg(s)
    assert np.abs(az).max() <= 35.2 + 1e-9 and np.abs(el).max() <= 38.6 + 1e-9
    assert np.abs(az).max() > 34.5 and np.abs(el).max() > 38.0
    assert s.num_rays == 24_000


def test_deterministic():
    for name in ("mid360", "avia", "mid70", "vlp16"):
        assert get_sensor(name) == get_sensor(name)


@pytest.mark.parametrize("bad", [0, -0.1, float("nan"), float("inf"), 1e-9, 1e6, "0.1", True])
def test_bad_integration_time(bad):
    with pytest.raises(SensorError):
        get_sensor("mid70", integration_time=bad)


def test_integration_time_rejected_for_spinning():
    with pytest.raises(SensorError, match="spinning"):
        get_sensor("vlp16", integration_time=0.1)


# ---------------------------------------------------------------- names


@pytest.mark.parametrize(
    "alias,name",
    [
        ("vlp16", "vlp16"),
        ("VLP-16", "vlp16"),
        ("vlp_16", "vlp16"),
        ("Velodyne VLP-16", "vlp16"),
        ("HDL-32E", "hdl32"),
        ("hdl32", "hdl32"),
        ("os1-64", "os1-64"),
        ("OS1_64", "os1-64"),
        ("ouster", "os1-64"),
        ("Mid-70", "mid70"),
        ("MID40", "mid40"),
        ("mid-360", "mid360"),
        ("Livox Avia", "avia"),
        ("  avia ", "avia"),
    ],
)
def test_aliases(alias, name):
    assert get_sensor(alias).name == name


def test_unknown_name():
    with pytest.raises(SensorError) as info:
        get_sensor("vlp17")
    message = str(info.value)
    assert "vlp16" in message and "mid70" in message
    assert "\n" not in message
    assert isinstance(info.value, Lf3pmError)


def test_lazy_top_level_import():
    import lf3pm

    assert lf3pm.get_sensor("vlp16").num_rays == 28_800
    assert lf3pm.Sensor is Sensor


# ---------------------------------------------------------------- Sensor validation


def _make(**over):
    fields = dict(
        name="t",
        description="d",
        directions=np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]),
        min_range=0.1,
        max_range=10.0,
        range_noise_sigma=0.01,
        horizontal_fov=1.0,
        approximate=False,
        source="test",
    )
    fields.update(over)
    return Sensor(**fields)


def test_sensor_valid_and_frozen():
    s = _make(directions=[[1, 0, 0]])
    assert s.directions.dtype == np.float64 and s.num_rays == 1
    with pytest.raises(AttributeError):
        s.name = "x"


@pytest.mark.parametrize(
    "over",
    [
        dict(min_range=0.0),
        dict(min_range=-1.0),
        dict(max_range=0.1),
        dict(max_range=0.05),
        dict(min_range=float("nan")),
        dict(max_range=float("inf")),
        dict(range_noise_sigma=-0.01),
        dict(directions=np.array([[1.0, 1.0, 0.0]])),
        dict(directions=np.array([[np.nan, 0.0, 0.0]])),
        dict(directions=np.zeros((0, 3))),
        dict(directions=np.array([1.0, 0.0, 0.0])),
        dict(directions=np.ones((2, 2))),
        dict(horizontal_fov=0.0),
        dict(horizontal_fov=7.0),
        dict(name=""),
        dict(min_range="1"),
    ],
)
def test_sensor_validation(over):
    with pytest.raises(SensorError):
        _make(**over)


# ---------------------------------------------------------------- YAML


def write(tmp_path: Path, text: str, name: str = "sensor.yaml") -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


SPIN_YAML = """\
name: my-16-beam
description: a VLP-16 look-alike
min_range: 0.5
max_range: 100.0
range_noise_sigma: 0.015
elevations_deg: [-15, -13, -11, -9, -7, -5, -3, -1, 1, 3, 5, 7, 9, 11, 13, 15]
azimuth_count: 1800
"""


def test_yaml_spinning_round_trip(tmp_path):
    path = write(tmp_path, SPIN_YAML)
    s = load_sensor_yaml(path)
    vlp = get_sensor("vlp16")
    assert s.name == "my-16-beam" and s.description == "a VLP-16 look-alike"
    assert (s.min_range, s.max_range, s.range_noise_sigma) == (0.5, 100.0, 0.015)
    assert s.horizontal_fov == pytest.approx(2 * math.pi)
    assert s.approximate is False and str(path) in s.source
    np.testing.assert_allclose(s.directions, vlp.directions, atol=1e-15)
    # via get_sensor, as a str and as a Path
    assert get_sensor(str(path)) == s
    assert get_sensor(path) == s


def test_yaml_spinning_partial_fov(tmp_path):
    path = write(
        tmp_path,
        "name: front\nmin_range: 0.2\nmax_range: 30\nelevations_deg: [0.0, 10]\n"
        "azimuth_count: 91\nhorizontal_fov_deg: 90\n",
    )
    s = load_sensor_yaml(path)
    assert s.num_rays == 182 and s.range_noise_sigma == 0.0
    assert s.horizontal_fov == pytest.approx(math.pi / 2)
    az, el = angles_deg(s)
    np.testing.assert_allclose(az[::2], np.linspace(-45, 45, 91), atol=1e-9)
    np.testing.assert_allclose(el[:2], [0.0, 10.0], atol=1e-9)  # listed order kept
    assert s.description  # default description


def test_yaml_pattern_round_trip(tmp_path):
    rng = np.random.default_rng(0)
    pattern = np.stack([rng.uniform(-0.5, 0.5, 1000), rng.uniform(-0.3, 0.3, 1000)], axis=1).astype(np.float32)
    (tmp_path / "pats").mkdir()
    np.save(tmp_path / "pats" / "p.npy", pattern)
    path = write(
        tmp_path,
        "name: custom-livox\nmin_range: 0.1\nmax_range: 50\nrange_noise_sigma: 0.02\n"
        "pattern_file: pats/p.npy\npoint_rate: 5000\nintegration_time: 0.1\n",
    )
    s = load_sensor_yaml(path)
    assert s.num_rays == 500 and s.name == "custom-livox"
    az, el = pattern[:500, 0].astype(np.float64), pattern[:500, 1].astype(np.float64)
    expected = np.stack([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)], axis=1)
    np.testing.assert_allclose(s.directions, expected, atol=1e-12)
    assert 0 < s.horizontal_fov <= 1.0 + 1e-6
    # override and ring buffer
    longer = get_sensor(str(path), integration_time=0.3)
    assert longer.num_rays == 1500
    np.testing.assert_array_equal(longer.directions[1000:], longer.directions[:500])
    # the bundled Mid-70 pattern through YAML gives the preset's rays
    write(
        tmp_path,
        f"name: m\nmin_range: 0.05\nmax_range: 130\npattern_file: {PATTERN_DIR / 'mid70.npy'}\n"
        "point_rate: 100000\nintegration_time: 0.1\n",
        "m70.yaml",
    )
    np.testing.assert_array_equal(load_sensor_yaml(tmp_path / "m70.yaml").directions, get_sensor("mid70").directions)


def test_yaml_spinning_rejects_integration_time(tmp_path):
    with pytest.raises(SensorError):
        get_sensor(str(write(tmp_path, SPIN_YAML)), integration_time=0.1)


BAD_YAML = {
    # id: (YAML text, key expected in the message)
    "unknown_key": (SPIN_YAML + "color: red\n", "color"),
    "missing_name": (SPIN_YAML.replace("name: my-16-beam\n", ""), "name"),
    "missing_min_range": (SPIN_YAML.replace("min_range: 0.5\n", ""), "min_range"),
    "missing_max_range": (SPIN_YAML.replace("max_range: 100.0\n", ""), "max_range"),
    "missing_azimuth_count": (SPIN_YAML.replace("azimuth_count: 1800\n", ""), "azimuth_count"),
    "missing_elevations": (
        SPIN_YAML.replace("elevations_deg: [-15, -13, -11, -9, -7, -5, -3, -1, 1, 3, 5, 7, 9, 11, 13, 15]\n", ""),
        "elevations_deg",
    ),
    "no_form": ("name: a\nmin_range: 1\nmax_range: 2\n", "elevations_deg"),
    "both_forms": (SPIN_YAML + "pattern_file: x.npy\n", "pattern_file"),
    "name_not_string": (SPIN_YAML.replace("name: my-16-beam", "name: [1, 2]"), "name"),
    "min_range_string": (SPIN_YAML.replace("min_range: 0.5", "min_range: near"), "min_range"),
    "min_range_bool": (SPIN_YAML.replace("min_range: 0.5", "min_range: true"), "min_range"),
    "min_range_negative": (SPIN_YAML.replace("min_range: 0.5", "min_range: -0.5"), "min_range"),
    "max_below_min": (SPIN_YAML.replace("max_range: 100.0", "max_range: 0.4"), "max_range"),
    "sigma_negative": (SPIN_YAML.replace("range_noise_sigma: 0.015", "range_noise_sigma: -1"), "range_noise_sigma"),
    "sigma_string": (SPIN_YAML.replace("range_noise_sigma: 0.015", "range_noise_sigma: small"), "range_noise_sigma"),
    "elevations_not_list": (
        SPIN_YAML.replace(
            "elevations_deg: [-15, -13, -11, -9, -7, -5, -3, -1, 1, 3, 5, 7, 9, 11, 13, 15]", "elevations_deg: 5"
        ),
        "elevations_deg",
    ),
    "elevations_item": (SPIN_YAML.replace("[-15, -13,", "[-15, x,"), "elevations_deg"),
    "elevations_empty": (
        SPIN_YAML.replace("[-15, -13, -11, -9, -7, -5, -3, -1, 1, 3, 5, 7, 9, 11, 13, 15]", "[]"),
        "elevations_deg",
    ),
    "elevation_out_of_range": (SPIN_YAML.replace("[-15, -13,", "[-95, -13,"), "elevations_deg"),
    "azimuth_count_float": (SPIN_YAML.replace("azimuth_count: 1800", "azimuth_count: 1800.5"), "azimuth_count"),
    "azimuth_count_zero": (SPIN_YAML.replace("azimuth_count: 1800", "azimuth_count: 0"), "azimuth_count"),
    "fov_too_big": (SPIN_YAML + "horizontal_fov_deg: 400\n", "horizontal_fov_deg"),
    "fov_string": (SPIN_YAML + "horizontal_fov_deg: wide\n", "horizontal_fov_deg"),
    "description_not_string": (SPIN_YAML.replace("description: a VLP-16 look-alike", "description: 3"), "description"),
    "pattern_missing_file": (
        "name: a\nmin_range: 0.1\nmax_range: 10\npattern_file: nowhere.npy\npoint_rate: 1000\nintegration_time: 0.1\n",
        "pattern_file",
    ),
    "pattern_missing_rate": (
        "name: a\nmin_range: 0.1\nmax_range: 10\npattern_file: ok.npy\nintegration_time: 0.1\n",
        "point_rate",
    ),
    "pattern_missing_time": (
        "name: a\nmin_range: 0.1\nmax_range: 10\npattern_file: ok.npy\npoint_rate: 1000\n",
        "integration_time",
    ),
    "pattern_rate_string": (
        "name: a\nmin_range: 0.1\nmax_range: 10\npattern_file: ok.npy\npoint_rate: fast\nintegration_time: 0.1\n",
        "point_rate",
    ),
    "pattern_time_zero": (
        "name: a\nmin_range: 0.1\nmax_range: 10\npattern_file: ok.npy\npoint_rate: 1000\nintegration_time: 0\n",
        "integration_time",
    ),
    "pattern_file_not_string": (
        "name: a\nmin_range: 0.1\nmax_range: 10\npattern_file: 12\npoint_rate: 1000\nintegration_time: 0.1\n",
        "pattern_file",
    ),
    "pattern_wrong_shape": (
        "name: a\nmin_range: 0.1\nmax_range: 10\npattern_file: bad_shape.npy\n"
        "point_rate: 1000\nintegration_time: 0.1\n",
        "pattern_file",
    ),
    "pattern_not_npy": (
        "name: a\nmin_range: 0.1\nmax_range: 10\npattern_file: junk.npy\npoint_rate: 1000\nintegration_time: 0.1\n",
        "pattern_file",
    ),
    "pattern_nan": (
        "name: a\nmin_range: 0.1\nmax_range: 10\npattern_file: nan.npy\npoint_rate: 1000\nintegration_time: 0.1\n",
        "pattern_file",
    ),
}


@pytest.mark.parametrize("case", sorted(BAD_YAML))
def test_bad_yaml(tmp_path, case):
    text, key = BAD_YAML[case]
    np.save(tmp_path / "ok.npy", np.zeros((10, 2)))
    np.save(tmp_path / "bad_shape.npy", np.zeros((10, 3)))
    np.save(tmp_path / "nan.npy", np.full((10, 2), np.nan))
    (tmp_path / "junk.npy").write_text("not numpy")
    path = write(tmp_path, text)
    with pytest.raises(SensorError) as info:
        load_sensor_yaml(path)
    message = str(info.value)
    assert "\n" not in message
    assert str(path) in message
    assert f"'{key}'" in message
    with pytest.raises(SensorError):  # same through get_sensor
        get_sensor(str(path))


@pytest.mark.parametrize("text", ["name: [unclosed\n", "- just\n- a list\n", "", "42\n"])
def test_yaml_not_a_mapping(tmp_path, text):
    path = write(tmp_path, text)
    with pytest.raises(SensorError) as info:
        load_sensor_yaml(path)
    assert "\n" not in str(info.value) and str(path) in str(info.value)


def test_yaml_file_missing(tmp_path):
    missing = tmp_path / "nope.yaml"
    with pytest.raises(SensorError, match="nope.yaml"):
        get_sensor(str(missing))
    with pytest.raises(SensorError, match="nope.yaml"):
        load_sensor_yaml(missing)


def test_docs_example_loads(tmp_path):
    """The full YAML example in docs/sensors.md is valid."""
    doc = (Path(__file__).resolve().parents[1] / "docs" / "sensors.md").read_text()
    blocks = [b.split("```", 1)[0] for b in doc.split("```yaml\n")[1:]]
    assert blocks
    for i, block in enumerate(blocks):
        np.save(tmp_path / "my_pattern.npy", np.zeros((100, 2)))
        s = load_sensor_yaml(write(tmp_path, block, f"doc{i}.yaml"))
        assert s.num_rays > 0


def test_presets_are_built_once_and_cannot_be_changed_in_place():
    """lf3pm.evaluate(map, pose, "vlp16") used to rebuild the VLP-16's rays on every
    call (2.4 ms; the OS1-64's 10 ms): a preset is now built once per process, so its
    rays must be read-only for the sharing to be safe."""
    first = get_sensor("vlp16")
    assert get_sensor("Velodyne VLP-16") is first
    with pytest.raises(ValueError):
        first.directions[0, 0] = 1.0
    assert get_sensor("mid70", integration_time=0.2) is not get_sensor("mid70")
