"""Map readers and writers (lf3pm.io): round trips, odd layouts, bad input, voxels."""

import os
from pathlib import Path

import laspy
import numpy as np
import pytest
from pypcd4 import Encoding, PointCloud
from shared_data import shared_file

import lf3pm.io.npy
from lf3pm.errors import MapError
from lf3pm.io import SUPPORTED_SUFFIXES, load_points, voxel_downsample, write_points

FLOAT32_SUFFIXES = (".pcd", ".ply")


def random_points(seed, n=1000, scale=50.0):
    return np.random.default_rng(seed).uniform(-scale, scale, size=(n, 3))


def as_float32(points):
    return points.astype(np.float32).astype(np.float64)


def expect_map_error(path, **kwargs):
    """Loads ``path``, expecting a one-line MapError that names the file; returns the message."""
    with pytest.raises(MapError) as info:
        load_points(path, **kwargs)
    message = str(info.value)
    assert "\n" not in message
    assert Path(path).name in message
    return message


def truncate(path, remove_bytes):
    data = path.read_bytes()
    path.write_bytes(data[: len(data) - remove_bytes])


def pcd_header(fields, sizes, types, points, data):
    return (
        f"# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS {' '.join(fields)}\n"
        f"SIZE {' '.join(map(str, sizes))}\nTYPE {' '.join(types)}\n"
        f"COUNT {' '.join('1' * len(fields))}\nWIDTH {points}\nHEIGHT 1\n"
        f"VIEWPOINT 0 0 0 1 0 0 0\nPOINTS {points}\nDATA {data}\n"
    ).encode()


# Extra fields of mixed types around (and between) x, y and z, as LiDAR drivers write them.
MIXED_DTYPE = np.dtype(
    [("timestamp", "<f8"), ("x", "<f4"), ("ring", "<u2"), ("y", "<f4"), ("intensity", "<f4"), ("z", "<f4")]
)


def mixed_records(seed, n):
    rng = np.random.default_rng(seed)
    records = np.zeros(n, dtype=MIXED_DTYPE)
    for axis in "xyz":
        records[axis] = rng.uniform(-30, 30, n)
    records["timestamp"] = 1.6e9 + rng.uniform(0, 0.1, n)
    records["ring"] = rng.integers(0, 64, n)
    records["intensity"] = rng.uniform(0, 255, n)
    return records


def xyz_of(records):
    return np.stack([records["x"], records["y"], records["z"]], axis=1).astype(np.float64)


def mixed_pcd_header(n, data):
    return pcd_header(
        MIXED_DTYPE.names,
        [MIXED_DTYPE[name].itemsize for name in MIXED_DTYPE.names],
        ["U" if MIXED_DTYPE[name].kind == "u" else "F" for name in MIXED_DTYPE.names],
        n,
        data,
    )


# --- round trips ------------------------------------------------------------------------------


@pytest.mark.parametrize("suffix", SUPPORTED_SUFFIXES)
def test_round_trip_every_format(tmp_path, suffix):
    points = random_points(seed=1)
    path = tmp_path / f"map{suffix}"
    write_points(path, points)
    loaded = load_points(path)
    assert loaded.dtype == np.float64 and loaded.shape == points.shape
    assert loaded.flags.c_contiguous
    if suffix in FLOAT32_SUFFIXES:
        np.testing.assert_array_equal(loaded, as_float32(points))
    elif suffix in (".las", ".laz"):
        np.testing.assert_allclose(loaded, points, rtol=0, atol=1e-6)
    else:
        np.testing.assert_array_equal(loaded, points)


@pytest.mark.parametrize("encoding", ["ascii", "binary", "binary_compressed"])
def test_pcd_round_trip_every_encoding(tmp_path, encoding):
    # Points on a coarse grid compress well, so binary_compressed really is compressed.
    rng = np.random.default_rng(2)
    points = rng.integers(-40, 40, size=(5000, 3)) * 0.25 + rng.uniform(-1e-3, 1e-3, size=(5000, 3))
    path = tmp_path / "map.pcd"
    write_points(path, points, encoding=encoding)
    assert f"DATA {encoding}\n".encode() in path.read_bytes()[:400]
    np.testing.assert_allclose(load_points(path), as_float32(points), rtol=0, atol=1e-9)


def test_pcd_default_encoding_is_binary(tmp_path):
    path = tmp_path / "map.pcd"
    write_points(path, random_points(seed=3, n=10))
    assert b"DATA binary\n" in path.read_bytes()[:400]


def test_ascii_pcd_with_one_point(tmp_path):
    path = tmp_path / "one.pcd"
    write_points(path, [[1.5, -2.25, 3.0]], encoding="ascii")
    np.testing.assert_array_equal(load_points(path), [[1.5, -2.25, 3.0]])


def test_las_stores_large_coordinates_to_the_micrometre(tmp_path):
    # UTM-like coordinates: offsets of hundreds of km, a cloud 100 m wide.
    points = random_points(seed=4) + [500_000.0, 4_000_000.0, 120.0]
    for suffix in (".las", ".laz"):
        path = tmp_path / f"utm{suffix}"
        write_points(path, points)
        np.testing.assert_allclose(load_points(path), points, rtol=0, atol=1e-6)


def test_las_wider_than_int32_micrometres_uses_a_coarser_step(tmp_path):
    points = random_points(seed=5, scale=10_000.0)  # 20 km wide: 1 µm steps would overflow int32
    write_points(tmp_path / "wide.las", points)
    np.testing.assert_allclose(load_points(tmp_path / "wide.las"), points, rtol=0, atol=1e-5)


def test_las_reader_uses_the_scaled_coordinates(tmp_path):
    # A file from another tool: centimetre steps and a large offset.
    points = np.round(random_points(seed=6, n=200), 2) + [1000.0, 2000.0, 0.0]
    header = laspy.LasHeader(point_format=3, version="1.2")
    header.offsets = [1000.0, 2000.0, 0.0]
    header.scales = [0.01, 0.01, 0.01]
    las = laspy.LasData(header)
    las.x, las.y, las.z = points.T
    las.write(tmp_path / "cm.las")
    np.testing.assert_allclose(load_points(tmp_path / "cm.las"), points, rtol=0, atol=1e-9)


def test_suffix_is_case_insensitive(tmp_path):
    points = random_points(seed=7, n=50)
    write_points(tmp_path / "MAP.PCD", points)
    np.testing.assert_array_equal(load_points(tmp_path / "MAP.PCD"), as_float32(points))


def test_write_replaces_an_existing_file_and_leaves_no_temporary(tmp_path):
    path = tmp_path / "map.npy"
    write_points(path, random_points(seed=8, n=10))
    newer = random_points(seed=9, n=20)
    write_points(str(path), newer)
    np.testing.assert_array_equal(load_points(path), newer)
    assert os.listdir(tmp_path) == ["map.npy"]


def test_failed_write_keeps_the_old_file(tmp_path, monkeypatch):
    path = tmp_path / "map.npy"
    old = random_points(seed=10, n=10)
    write_points(path, old)

    def crash(fp, points):
        fp.write(b"partial")
        raise RuntimeError("disk on fire")

    monkeypatch.setattr(lf3pm.io.npy, "write_npy", crash)
    with pytest.raises(RuntimeError):
        write_points(path, random_points(seed=11, n=10))
    np.testing.assert_array_equal(load_points(path), old)
    assert os.listdir(tmp_path) == ["map.npy"]


# --- PCD with extra fields -------------------------------------------------------------------


@pytest.mark.parametrize("data", ["binary", "ascii"])
def test_pcd_with_mixed_type_fields_hand_written(tmp_path, data):
    records = mixed_records(seed=12, n=300)
    path = tmp_path / "lidar.pcd"
    if data == "binary":
        body = records.tobytes()  # 26-byte records, no padding
        assert len(body) == 300 * 26
    else:
        body = "".join(" ".join(map(repr, row)) + "\n" for row in records.tolist()).encode()
    path.write_bytes(mixed_pcd_header(300, data) + body)
    np.testing.assert_array_equal(load_points(path), xyz_of(records))


def test_binary_pcd_and_las_read_in_chunks(tmp_path, monkeypatch):
    """The chunked readers (records straight into the float64 result) read what pypcd4 and
    laspy read whole, across chunk boundaries."""
    import lf3pm.io.las
    import lf3pm.io.pcd

    monkeypatch.setattr(lf3pm.io.pcd, "_CHUNK_RECORDS", 7)
    monkeypatch.setattr(lf3pm.io.las, "_CHUNK_POINTS", 7)
    records = mixed_records(seed=18, n=50)
    pcd = tmp_path / "lidar.pcd"
    pcd.write_bytes(mixed_pcd_header(50, "binary") + records.tobytes())
    np.testing.assert_array_equal(load_points(pcd), xyz_of(records))
    points = random_points(seed=19, n=50)
    for suffix in (".las", ".laz"):
        path = tmp_path / f"map{suffix}"
        write_points(path, points)
        las = laspy.read(path)
        np.testing.assert_array_equal(load_points(path), np.c_[las.x, las.y, las.z])


def test_pcd_with_mixed_type_fields_binary_compressed(tmp_path):
    records = mixed_records(seed=13, n=2000)
    records["x"] = np.round(records["x"])  # compressible
    cloud = PointCloud.from_points(
        [records[name] for name in MIXED_DTYPE.names],
        MIXED_DTYPE.names,
        [MIXED_DTYPE[name] for name in MIXED_DTYPE.names],
    )
    path = tmp_path / "lidar.pcd"
    cloud.save(path, encoding=Encoding.BINARY_COMPRESSED)
    assert b"DATA binary_compressed\n" in path.read_bytes()[:400]
    np.testing.assert_array_equal(load_points(path), xyz_of(records))


def test_pcd_with_double_coordinates(tmp_path):
    points = random_points(seed=14, n=100) + 1e6
    path = tmp_path / "double.pcd"
    path.write_bytes(pcd_header("xyz", [8, 8, 8], "FFF", 100, "binary") + points.tobytes())
    np.testing.assert_array_equal(load_points(path), points)


# --- NumPy variants --------------------------------------------------------------------------


def test_npy_with_more_than_three_columns_keeps_xyz(tmp_path):
    table = np.random.default_rng(15).normal(size=(100, 5)).astype(np.float32)
    np.save(tmp_path / "table.npy", table)
    loaded = load_points(tmp_path / "table.npy")
    np.testing.assert_array_equal(loaded, table[:, :3].astype(np.float64))
    assert loaded.flags.c_contiguous and loaded.flags.writeable


def test_npy_of_integers(tmp_path):
    grid = np.arange(30, dtype=np.int32).reshape(10, 3)
    np.save(tmp_path / "grid.npy", grid)
    np.testing.assert_array_equal(load_points(tmp_path / "grid.npy"), grid)


@pytest.mark.parametrize("layout", ["float64", "big-endian float32, 4 columns", "fortran"])
def test_npy_read_in_chunks_equals_numpy(tmp_path, monkeypatch, layout):
    """The chunked reader (rows straight into the float64 result) reads what np.load reads,
    across chunk boundaries and for every layout."""
    monkeypatch.setattr(lf3pm.io.npy, "_CHUNK_ROWS", 7)
    table = np.random.default_rng(17).normal(size=(50, 4))
    if layout == "float64":
        table = table[:, :3].copy()
    elif layout.startswith("big"):
        table = table.astype(">f4")
    else:
        table = np.asfortranarray(table)
    np.save(tmp_path / "t.npy", table)
    loaded = load_points(tmp_path / "t.npy")
    np.testing.assert_array_equal(loaded, np.load(tmp_path / "t.npy")[:, :3].astype(np.float64))
    assert loaded.flags.c_contiguous and loaded.dtype == np.float64


def test_npz_prefers_the_array_named_points(tmp_path):
    points = random_points(seed=16, n=40)
    np.savez(tmp_path / "map.npz", colors=np.zeros((40, 3)), points=points, poses=np.eye(4))
    np.testing.assert_array_equal(load_points(tmp_path / "map.npz"), points)


def test_npz_with_one_unnamed_array(tmp_path):
    points = random_points(seed=17, n=40)
    np.savez_compressed(tmp_path / "map.npz", points)  # stored as arr_0
    np.testing.assert_array_equal(load_points(tmp_path / "map.npz"), points)


def test_npz_with_several_arrays_but_no_points_is_refused(tmp_path):
    np.savez(tmp_path / "map.npz", a=np.zeros((4, 3)), b=np.ones((4, 3)))
    assert "points" in expect_map_error(tmp_path / "map.npz")


def test_npz_with_no_array_is_refused(tmp_path):
    np.savez(tmp_path / "map.npz")
    assert "no arrays" in expect_map_error(tmp_path / "map.npz")


# --- NaN / Inf -------------------------------------------------------------------------------


@pytest.mark.parametrize("suffix", [".npy", ".pcd"])
def test_points_with_nan_or_inf_are_dropped_with_a_count(tmp_path, suffix):
    points = random_points(seed=18, n=10)
    points[2, 0] = np.nan
    points[5, 2] = np.inf
    points[7] = [-np.inf, np.nan, 1.0]
    path = tmp_path / f"holes{suffix}"
    if suffix == ".npy":
        np.save(path, points)
    else:
        PointCloud.from_xyz_points(points).save(path)
    with pytest.warns(UserWarning, match=r"dropped 3 of 10 points"):
        loaded = load_points(path)
    expected = np.delete(points, [2, 5, 7], axis=0)
    np.testing.assert_array_equal(loaded, as_float32(expected) if suffix == ".pcd" else expected)


def test_every_point_non_finite_is_refused(tmp_path):
    points = np.full((5, 3), np.nan)
    points[0, 0] = np.inf
    np.save(tmp_path / "void.npy", points)
    assert "no finite points" in expect_map_error(tmp_path / "void.npy")


# --- bad input -------------------------------------------------------------------------------


def test_missing_file(tmp_path):
    assert "no such file" in expect_map_error(tmp_path / "nowhere.pcd")


def test_directory_is_not_a_map(tmp_path):
    (tmp_path / "folder.pcd").mkdir()
    assert "not a regular file" in expect_map_error(tmp_path / "folder.pcd")


def test_unknown_suffix_lists_the_supported_ones(tmp_path):
    (tmp_path / "map.xyz").write_text("1 2 3\n")
    message = expect_map_error(tmp_path / "map.xyz")
    assert ".xyz" in message
    assert all(suffix in message for suffix in SUPPORTED_SUFFIXES)


def test_no_suffix(tmp_path):
    (tmp_path / "map").write_text("1 2 3\n")
    assert "unknown suffix" in expect_map_error(tmp_path / "map")


@pytest.mark.parametrize("suffix", [".pcd", ".npy", ".npz"])
def test_empty_cloud(tmp_path, suffix):
    path = tmp_path / f"empty{suffix}"
    if suffix == ".pcd":
        path.write_bytes(pcd_header("xyz", [4, 4, 4], "FFF", 0, "binary"))
    elif suffix == ".npy":
        np.save(path, np.empty((0, 3)))
    else:
        np.savez(path, points=np.empty((0, 3)))
    assert "no points" in expect_map_error(path)


@pytest.mark.parametrize("remove_bytes", [1, 12, 6000])
def test_truncated_binary_pcd(tmp_path, remove_bytes):
    # 12 bytes is one whole record: pypcd4 alone would return 999 points silently.
    path = tmp_path / "cut.pcd"
    write_points(path, random_points(seed=19), encoding="binary")
    truncate(path, remove_bytes)
    assert "truncated" in expect_map_error(path)


def test_binary_pcd_with_mixed_fields_cut_mid_record(tmp_path):
    path = tmp_path / "cut.pcd"
    body = mixed_records(seed=20, n=100).tobytes()
    path.write_bytes(mixed_pcd_header(100, "binary") + body[:-30])
    assert "truncated" in expect_map_error(path)


def test_truncated_compressed_pcd(tmp_path):
    path = tmp_path / "cut.pcd"
    compressible = np.repeat(np.arange(3000.0)[:, None], 3, axis=1)
    write_points(path, compressible, encoding="binary_compressed")
    assert b"DATA binary_compressed" in path.read_bytes()[:400]
    truncate(path, 100)
    assert "truncated" in expect_map_error(path)


@pytest.mark.parametrize("suffix", [".npy", ".npz", ".ply", ".las", ".laz"])
@pytest.mark.parametrize("remove_bytes", [1, 200])
def test_truncated_files(tmp_path, suffix, remove_bytes):
    path = tmp_path / f"cut{suffix}"
    write_points(path, random_points(seed=21))
    truncate(path, remove_bytes)
    expect_map_error(path)


def test_las_cut_at_a_record_boundary(tmp_path):
    # Point format 0 records are 20 bytes; laspy alone would return 999 points.
    path = tmp_path / "cut.las"
    write_points(path, random_points(seed=22))
    truncate(path, 20)
    assert "truncated" in expect_map_error(path)


def test_garbage_pcd(tmp_path):
    (tmp_path / "noise.pcd").write_bytes(np.random.default_rng(23).bytes(500))
    expect_map_error(tmp_path / "noise.pcd")


def test_pcd_without_z(tmp_path):
    path = tmp_path / "flat.pcd"
    body = np.zeros(8, np.float32).tobytes()
    path.write_bytes(pcd_header("xy", [4, 4], "FF", 4, "binary") + body)
    assert "z" in expect_map_error(path)


def test_ply_without_z(tmp_path):
    path = tmp_path / "flat.ply"
    path.write_text(
        "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nend_header\n0 0\n1 1\n"
    )
    assert "z" in expect_map_error(path)


@pytest.mark.parametrize("shape", [(10, 2), (30,), (2, 5, 3)])
def test_npy_of_the_wrong_shape(tmp_path, shape):
    np.save(tmp_path / "bad.npy", np.zeros(shape))
    assert "shape" in expect_map_error(tmp_path / "bad.npy")


def test_npz_of_the_wrong_shape(tmp_path):
    np.savez(tmp_path / "bad.npz", points=np.zeros((10, 2)))
    assert "shape" in expect_map_error(tmp_path / "bad.npz")


def test_npy_of_strings(tmp_path):
    np.save(tmp_path / "words.npy", np.array([["a", "b", "c"]]))
    expect_map_error(tmp_path / "words.npy")


def test_npy_of_objects_is_not_unpickled(tmp_path):
    np.save(tmp_path / "objects.npy", np.array([[1, 2, None]], dtype=object), allow_pickle=True)
    expect_map_error(tmp_path / "objects.npy")


@pytest.mark.parametrize("voxel", [0, -0.5, float("nan"), float("inf"), "big"])
def test_voxel_must_be_positive(tmp_path, voxel):
    write_points(tmp_path / "map.npy", random_points(seed=24, n=10))
    with pytest.raises(MapError, match="voxel"):
        load_points(tmp_path / "map.npy", voxel=voxel)
    with pytest.raises(MapError, match="voxel"):
        voxel_downsample(random_points(seed=24, n=10), voxel)


def test_write_refuses_bad_requests(tmp_path):
    points = random_points(seed=25, n=10)
    for path, kwargs, points_, problem in [
        ("map.txt", {}, points, "unknown suffix"),
        ("map.ply", {"encoding": "ascii"}, points, "only be chosen for .pcd"),
        ("map.pcd", {"encoding": "zip"}, points, "unknown PCD encoding"),
        ("map.pcd", {}, points[:, :2], "shape"),
        ("map.pcd", {}, np.empty((0, 3)), "no points"),
        ("map.pcd", {}, np.full((2, 3), np.nan), "finite"),
        ("missing/map.pcd", {}, points, "cannot write"),
    ]:
        with pytest.raises(MapError, match=problem) as info:
            write_points(tmp_path / path, points_, **kwargs)
        assert "\n" not in str(info.value) and Path(path).name in str(info.value)
    assert os.listdir(tmp_path) == []


# --- voxel downsampling ----------------------------------------------------------------------


def test_voxel_downsample_hand_made_example():
    points = np.array(
        [
            [0.1, 0.1, 0.1],
            [0.3, 0.5, 0.9],  # cell (0, 0, 0)
            [1.5, 0.2, 0.2],  # cell (1, 0, 0)
            [-0.5, -0.5, -0.5],
            [-0.1, -0.9, -0.3],  # cell (-1, -1, -1)
            [0.5, 2.5, 0.5],  # cell (0, 2, 0)
        ]
    )
    expected = np.array(
        [
            [-0.3, -0.7, -0.4],
            [0.2, 0.3, 0.5],
            [0.5, 2.5, 0.5],
            [1.5, 0.2, 0.2],
        ]
    )
    result = voxel_downsample(points, 1.0)
    np.testing.assert_allclose(result, expected, rtol=0, atol=1e-12)
    assert result.flags.c_contiguous and result.dtype == np.float64
    shuffled = points[np.random.default_rng(26).permutation(len(points))]
    np.testing.assert_allclose(voxel_downsample(shuffled, 1.0), expected, rtol=0, atol=1e-12)


def reference_downsample(points, voxel):
    cells = {}
    for point in points:
        cells.setdefault(tuple(np.floor(point / voxel).astype(np.int64)), []).append(point)
    return np.array([np.mean(cells[key], axis=0) for key in sorted(cells)])


@pytest.mark.parametrize("spread, voxel", [(3.0, 0.5), (1e6, 1e-3)])
def test_voxel_downsample_matches_a_reference(spread, voxel):
    # The second case spans ~2e9 cells per axis: too many for one int64 key, the row path.
    rng = np.random.default_rng(27)
    points = rng.uniform(-spread, spread, size=(400, 3))
    neighbours = points[:200] + rng.uniform(-1e-4, 1e-4, size=(200, 3)) * voxel
    points = np.concatenate([points, neighbours])
    result = voxel_downsample(points, voxel)
    expected = reference_downsample(points, voxel)
    assert len(result) == len(expected) < len(points)
    np.testing.assert_allclose(result, expected, rtol=1e-12, atol=1e-12 * spread)


def test_voxel_downsample_of_nothing():
    assert voxel_downsample(np.empty((0, 3)), 0.1).shape == (0, 3)


def test_voxel_downsample_refuses_non_finite_points_and_absurd_grids():
    with pytest.raises(MapError, match="finite"):
        voxel_downsample([[0.0, 0.0, np.nan], [1.0, 1.0, 1.0]], 0.1)
    with pytest.raises(MapError, match="too small"):
        voxel_downsample([[0.0, 0.0, 0.0], [1e10, 0.0, 0.0]], 1e-10)


def test_load_points_with_voxel(tmp_path):
    points = random_points(seed=28, n=2000, scale=5.0)
    write_points(tmp_path / "map.npy", points)
    downsampled = load_points(tmp_path / "map.npy", voxel=1.0)
    np.testing.assert_array_equal(downsampled, voxel_downsample(points, 1.0))
    assert len(downsampled) <= 1000


# --- real scans ------------------------------------------------------------------------------


def test_real_indoor_scan():
    points = load_points(shared_file("indoor_pcl_room_scan1.pcd"))
    assert points.shape == (112_586, 3) and points.dtype == np.float64 and points.flags.c_contiguous
    assert np.isfinite(points).all()


def test_real_outdoor_scan_with_mixed_fields():
    path = shared_file("outdoor_urban64_2021-10-26-16-21-29-468.pcd")
    points = load_points(path)
    assert points.shape == (80_787, 3)
    # Independent decode: x y z intensity (float32), ring (uint16), timestamp (float64).
    raw = path.read_bytes()
    start = raw.index(b"DATA binary\n") + len(b"DATA binary\n")
    layout = np.dtype(
        [("x", "<f4"), ("y", "<f4"), ("z", "<f4"), ("intensity", "<f4"), ("ring", "<u2"), ("timestamp", "<f8")]
    )
    records = np.frombuffer(raw[start:], dtype=layout)
    assert len(records) == 80_787
    np.testing.assert_array_equal(points, xyz_of(records))


@pytest.mark.parametrize("encoding", ["binary", "ascii", "binary_compressed"])
def test_a_header_declaring_more_than_the_file_holds_is_refused_before_reading(tmp_path, encoding):
    # 15,000 points whose z has a COUNT of 10^9: 60 TB declared in a file of under 200 KB.
    header = (
        "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1000000000\nWIDTH 15000\n"
        f"HEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 15000\nDATA {encoding}\n"
    ).encode()
    body = b"0 0 0\n" * 15000 if encoding == "ascii" else np.zeros(45000, np.float32).tobytes()
    path = tmp_path / f"claims_too_much_{encoding}.pcd"
    path.write_bytes(header + body)
    message = expect_map_error(path)
    assert "truncated or corrupt PCD file" in message and "15,000 points" in message
