"""Tile crops and the Ray engine: both write the store a whole-map local build writes,
bitwise, also when a worker is killed mid-task; bad cluster input is one line."""

import dataclasses
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import lf3pm
from lf3pm.solm import build_solm, make_grid
from lf3pm.solm.store import CHANNELS, MASKS

ray = pytest.importorskip("ray")

ARRAYS = CHANNELS + MASKS + ("ground_z", "done")


@pytest.fixture(scope="module")
def town():
    """A 70 x 70 m town and a VLP-16 of 6 m range on a 24 x 24 m grid of 2 x 2 tiles: each
    tile's crop (tile + 6 + r_max + sqrt 5 m) is a third of the map, so crops matter."""
    world = lf3pm.load_map(lf3pm.build_scene("houses").points)
    sensor = dataclasses.replace(lf3pm.get_sensor("vlp16"), max_range=6.0)
    lo = world.bounds[0]
    grid = make_grid(world, "r2", 1.5, bounds=(lo[0] + 5, lo[1] + 5, lo[0] + 29, lo[1] + 29))
    return world, sensor, grid


@pytest.fixture(scope="module")
def whole(town, tmp_path_factory):
    world, sensor, grid = town
    path = tmp_path_factory.mktemp("whole") / "s.zarr"
    build_solm(world, sensor, grid, path, tile=8, threads=2)
    return path


@pytest.fixture(scope="module")
def cluster():
    ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False, configure_logging=False)
    yield
    ray.shutdown()


def assert_same_store(a: Path, b: Path):
    import zarr

    ga, gb = zarr.open_group(str(a), mode="r"), zarr.open_group(str(b), mode="r")
    assert dict(ga.attrs) | {"map_source": None} == dict(gb.attrs) | {"map_source": None}
    for name in ARRAYS:
        x, y = ga[name][...], gb[name][...]
        assert x.dtype == y.dtype and x.tobytes() == y.tobytes(), name  # bitwise, NaNs included
    assert ga["done"][...].all()


@pytest.mark.slow
def test_the_crop_margin_holds_what_a_tile_sees(town):
    from lf3pm.solm.tiles import crop_margin

    world = town[0]
    neighbour = world.association_params["max_neighbor_distance"]
    job = _job(town)
    disc = max(min(3 * world.index.cell_size, neighbour), 0.75 * world.index.median_spacing)
    assert crop_margin(job, world) == pytest.approx(6.0 + disc + neighbour)
    crop = world.crop(job.bounds(0, 0), crop_margin(job, world))
    assert 0.1 * world.size < crop.size < 0.6 * world.size


def _job(town):
    from lf3pm.config import ScanConfig, SolmConfig
    from lf3pm.solm.tiles import make_job

    world, sensor, grid = town
    return make_job(sensor, grid, ScanConfig(noise=sensor.range_noise_sigma), solm=SolmConfig(tile=8))


@pytest.mark.slow
def test_crop_build_equals_the_whole_map_build_bitwise(town, whole, tmp_path):
    world, sensor, grid = town
    build_solm(world, sensor, grid, tmp_path / "c.zarr", tile=8, threads=2, crop=True)
    assert_same_store(whole, tmp_path / "c.zarr")


@pytest.mark.slow
def test_a_map_not_indexed_whole_builds_the_same_store(town, whole, tmp_path):
    from lf3pm import _core
    from lf3pm.map import load_map_points

    world, sensor, grid = town
    points = load_map_points(lf3pm.build_scene("houses").points)
    assert points.sha256 == world.sha256 and points.frame == world.frame
    assert points.frame == _core.map_frame(points.points, _core.MapParams())
    # MapPoints above crop_above are built tile by tile on crops; below it, indexed whole.
    assert build_solm(points, sensor, grid, tmp_path / "p.zarr", tile=8, threads=2, crop_above=1000)["on_crops"]
    assert_same_store(whole, tmp_path / "p.zarr")
    assert not build_solm(points, sensor, grid, tmp_path / "q.zarr", tile=8, threads=2)["on_crops"]
    assert_same_store(whole, tmp_path / "q.zarr")


@pytest.mark.slow
def test_the_cli_builds_a_map_above_crop_above_tile_by_tile(tmp_path):
    path = tmp_path / "boxes.npy"
    np.save(path, lf3pm.build_scene("boxes").points)
    stores = {}
    for name, extra in (("whole", []), ("crops", ["--crop-above", "1000"])):
        done = run_cli("solm", "build", path, "-o", tmp_path / f"{name}.zarr", "--res", "1", *extra)
        assert done.returncode == 0, done.stderr
        stores[name] = tmp_path / f"{name}.zarr"
    assert "built tile by tile on crops" in done.stderr
    assert_same_store(stores["whole"], stores["crops"])


@pytest.mark.slow
def test_ray_engine_equals_the_local_engine_bitwise(town, whole, cluster, tmp_path):
    world, sensor, grid = town
    calls = []
    build_solm(
        world,
        sensor,
        grid,
        tmp_path / "r.zarr",
        tile=8,
        engine="ray",
        progress=lambda cells, total: calls.append((cells, total)),
    )
    assert_same_store(whole, tmp_path / "r.zarr")
    assert sum(c for c, _ in calls) == calls[0][1] == grid.nx * grid.ny


@pytest.mark.slow
def test_an_interrupted_cluster_build_resumes(town, whole, cluster, tmp_path):
    world, sensor, grid = town
    out = build_solm(world, sensor, grid, tmp_path / "r.zarr", tile=8, engine="ray", max_tiles=2)
    assert out["built_now"] == 2 and not out["complete"]
    out = build_solm(world, sensor, grid, tmp_path / "r.zarr", tile=8, engine="ray")
    assert out["built_now"] == out["tiles"] - 2 and out["complete"]
    assert_same_store(whole, tmp_path / "r.zarr")


@pytest.mark.slow
def test_a_killed_worker_is_retried_and_changes_nothing(town, whole, cluster, tmp_path, monkeypatch):
    """The first attempt at one tile kills its worker process (os._exit, as a node
    lost mid-tile would); Ray reruns the task and the store is the local build's."""
    import lf3pm.solm.cluster as cluster_module

    world, sensor, grid = town
    original, marker = cluster_module.solm_tile, str(tmp_path / "killed")

    def dies_once(*args):  # nested: Ray ships it by value to the workers
        import os

        if args[6:8] == (0, 0) and not os.path.exists(marker):
            open(marker, "w").close()
            os._exit(1)
        return original(*args)

    monkeypatch.setattr(cluster_module, "solm_tile", dies_once)
    out = build_solm(world, sensor, grid, tmp_path / "k.zarr", tile=8, engine="ray")
    assert Path(marker).exists(), "the tile's first attempt did not run"
    assert out["complete"]
    assert_same_store(whole, tmp_path / "k.zarr")


def run_cli(*args):
    return subprocess.run(
        [sys.executable, "-m", "lf3pm.cli", *map(str, args)], capture_output=True, text=True, timeout=120
    )


@pytest.mark.slow
@pytest.mark.parametrize(
    "address, message",
    [("127.0.0.1:1", "no Ray head answers at 127.0.0.1:1"), ("nonsense", "--address must be HOST:PORT")],
)
def test_an_unreachable_cluster_is_one_line(tmp_path, address, message):
    path = tmp_path / "boxes.npy"
    np.save(path, lf3pm.build_scene("boxes").points)
    done = run_cli(
        "solm", "build", path, "-o", tmp_path / "s.zarr", "--res", "2", "--engine", "ray", "--address", address
    )
    lines = done.stderr.strip().splitlines()
    assert done.returncode == 2 and len(lines) == 1 and message in lines[0], done.stderr
    assert not (tmp_path / "s.zarr").exists()


@pytest.mark.slow
def test_a_store_in_a_missing_or_unwritable_folder_is_refused_before_the_cluster_starts(tmp_path):
    path = tmp_path / "boxes.npy"
    np.save(path, lf3pm.build_scene("boxes").points)
    done = run_cli("solm", "build", path, "-o", tmp_path / "no" / "s.zarr", "--res", "2", "--engine", "ray")
    assert done.returncode == 2 and "does not exist" in done.stderr and "Traceback" not in done.stderr
    # A regular file where the folder should be: as a read-only disk, even for root.
    (tmp_path / "file").write_text("")
    done = run_cli("solm", "build", path, "-o", tmp_path / "file" / "s.zarr", "--res", "2", "--engine", "ray")
    assert done.returncode == 2 and "is not a folder" in done.stderr and "Traceback" not in done.stderr
    done = run_cli("solm", "build", path, "-o", tmp_path / "s.zarr", "--res", "2", "--engine", "spark")
    assert done.returncode == 2 and "unknown engine 'spark'" in done.stderr


@pytest.mark.slow
def test_a_full_disk_under_the_ray_engine_is_the_local_engines_one_line(town, whole, cluster, tmp_path, mounted):
    """A worker's StorageError keeps its class through Ray: the build says, in one line,
    which tile's chunk failed, what it kept and how to resume, and the rerun with space
    freed completes to the local engine's store."""
    from lf3pm.errors import StorageError

    world, sensor, grid = town
    disk = mounted("size=1m")
    # Room for the store's metadata and about half its 340 kB of tiles.
    (disk / "filler").write_bytes(b"\0" * (1024 * 1024 - 80 * 1024))
    with pytest.raises(StorageError, match="failed on the cluster") as caught:
        build_solm(world, sensor, grid, disk / "r.zarr", tile=8, engine="ray")
    assert "\n" not in str(caught.value) and "resume" in str(caught.value)
    (disk / "filler").unlink()
    assert build_solm(world, sensor, grid, disk / "r.zarr", tile=8, engine="ray")["complete"]
    assert_same_store(disk / "r.zarr", whole)
