"""The r3yaw SOLM (issue 43, item 2): every yaw bin at every height, the body level and the
LiDAR on the quadrotor's mount. A cell equals evaluate() at that sensor pose; where the
mount and sensor make every bin see the same rays, one cast per cell gives every bin the
value each bin's own cast gives; the minimum over yaw and its argmin; interpolation."""

from __future__ import annotations

import math

import numpy as np
import pytest

import lf3pm
from lf3pm import _core
from lf3pm.errors import Lf3pmError
from lf3pm.flight import MOUNTS
from lf3pm.metric import eval_params
from lf3pm.scenes import build_scene
from lf3pm.solm import Solm, build_solm, make_grid

BOUNDS = (-2.0, -2.0, 2.0, 2.0)


@pytest.fixture(scope="module")
def boxes():
    return lf3pm.load_map(build_scene("boxes").points)


def body(x, y, z, yaw):
    c, s = math.cos(yaw), math.sin(yaw)
    return np.array([[c, -s, 0, x], [s, c, 0, y], [0, 0, 1, z], [0, 0, 0, 1.0]])


def cast(world, sensor, pose, stream=0):
    params = eval_params(sensor.min_range, sensor.max_range, noise=0.0, stream=stream)
    return _core.evaluate(world.index, np.ascontiguousarray(pose), sensor.directions, params).metric.q_n


@pytest.fixture(scope="module")
def down20(boxes, tmp_path_factory):
    """VLP-16 pitched 20 degrees down, 4 yaw bins at two heights, noise-free."""
    grid = make_grid(boxes, "r3yaw", 1.0, bounds=BOUNDS, yaw_bins=4, z_levels=(1.0, 2.0))
    path = tmp_path_factory.mktemp("solm") / "down20.zarr"
    build_solm(boxes, "vlp16", grid, path, noise=0.0, mount="down20", tile=2)
    return Solm.open(path)


def test_an_r3yaw_cell_is_the_metric_of_the_lidar_on_its_mount_at_that_height_and_yaw(boxes, down20):
    assert down20.grid_spec.shape == (8, 4, 4) and down20.attrs["mount"]["name"] == "down20"
    assert down20.attrs["yaw_once"] is False  # the pitched sensor sees other rays at each yaw
    x, y, z, yaw = down20.grid()
    q = down20.channel("q_n")
    sensor = lf3pm.get_sensor("vlp16")
    mount = MOUNTS["down20"].matrix()
    checked = 0
    for k, iy, ix in np.argwhere(np.isfinite(q))[::5]:
        pose = body(x[k, iy, ix], y[k, iy, ix], z[k, iy, ix], yaw[k, iy, ix]) @ mount
        assert q[k, iy, ix] == pytest.approx(cast(boxes, sensor, pose), rel=1e-6)  # stored as float32
        checked += 1
    assert checked >= 5
    # The four bins of one cell differ: the sensor looks down in four directions.
    k, iy, ix = np.argwhere(np.isfinite(q))[0]
    assert len({round(float(v), 6) for v in q[k - k % 4 : k - k % 4 + 4, iy, ix]}) > 1


def test_the_minimum_over_yaw_and_the_query(down20):
    low, best = down20.over_yaw("q_n")
    data = down20.channel("q_n").reshape(2, 4, 4, 4)
    finite = np.isfinite(low)
    assert finite.sum() > 10 and np.array_equal(finite, np.isfinite(data).any(axis=1))
    cells = data.transpose(0, 2, 3, 1)[finite]  # (cells, bins)
    np.testing.assert_array_equal(low[finite], cells.min(axis=1))
    np.testing.assert_array_equal(best[finite], down20.grid_spec.yaws()[cells.argmin(axis=1)])
    # At cell centres the query returns the stored value; its gradient is the finite difference.
    x, y, z, yaw = down20.grid()
    k, iy, ix = 4 + 1, 1, 2  # height 2 m, bin 1
    value, grad = down20.query(x[k, iy, ix], y[k, iy, ix], yaw[k, iy, ix], z=z[k, iy, ix])
    assert value == pytest.approx(float(down20.channel("q_n")[k, iy, ix]), rel=1e-12)
    p = np.array([x[k, iy, ix] + 0.3, y[k, iy, ix] + 0.2, 1.4, yaw[k, iy, ix] + 0.4])
    h = 1e-6
    _, g = down20.query(p[0], p[1], p[3], z=p[2])
    for axis, order in ((0, 0), (1, 1), (2, 2), (3, 3)):
        up, dn = p.copy(), p.copy()
        up[axis] += h
        dn[axis] -= h
        numeric = (down20.query(up[0], up[1], up[3], z=up[2])[0] - down20.query(dn[0], dn[1], dn[3], z=dn[2])[0]) / (
            2 * h
        )
        assert g[order] == pytest.approx(numeric, rel=1e-5, abs=1e-9)


def test_over_yaw_needs_yaw_bins_at_heights(boxes, tmp_path):
    grid = make_grid(boxes, "r2", 2.0, bounds=BOUNDS)
    build_solm(boxes, "vlp16", grid, tmp_path / "r2.zarr", noise=0.0)
    with pytest.raises(Lf3pmError, match="over_yaw needs an r3yaw SOLM"):
        Solm.open(tmp_path / "r2.zarr").over_yaw()


def test_a_level_spinning_lidar_on_the_body_axis_is_cast_once_for_every_yaw(boxes, tmp_path):
    """The top mount keeps a VLP-16 (1800 columns) level on the body's axis: turning the body
    by one of 8 bins only permutes its rays, so every bin takes bin 0's cast; each equals the
    bin's own cast to the Gram's summation order (stored as float32: relative 1e-6)."""
    grid = make_grid(boxes, "r3yaw", 1.0, bounds=BOUNDS, yaw_bins=8, z_levels=(1.5,))
    path = tmp_path / "top.zarr"
    build_solm(boxes, "vlp16", grid, path, noise=0.0, mount="top", tile=4)
    solm = Solm.open(path)
    assert solm.attrs["yaw_once"] is True
    x, y, z, yaw = solm.grid()
    q = solm.channel("q_n")
    sensor = lf3pm.get_sensor("vlp16")
    iy, ix = np.argwhere(np.isfinite(q[0]))[3]
    for b in range(8):
        pose = body(x[b, iy, ix], y[b, iy, ix], z[b, iy, ix], yaw[b, iy, ix]) @ MOUNTS["top"].matrix()
        assert q[b, iy, ix] == pytest.approx(cast(boxes, sensor, pose), rel=1e-6)
    # A Livox pattern is no spinning sensor, and a mount off the axis moves the sensor.
    for sensor_name, mount in (("mid70", "top"), ("vlp16", "down20")):
        other = make_grid(boxes, "r3yaw", 2.0, bounds=BOUNDS, yaw_bins=8, z_levels=(1.5,))
        out = tmp_path / f"{sensor_name}_{mount}.zarr"
        build_solm(boxes, sensor_name, other, out, noise=0.0, mount=mount, max_tiles=0)
        assert _attrs(out)["yaw_once"] is False


def _attrs(path):
    import zarr

    return dict(zarr.open_group(str(path), mode="r").attrs)
