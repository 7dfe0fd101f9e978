"""A map an experiment plans on: where it comes from and how its SOLM is built."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from lf3pm.config import DEFAULTS
from lf3pm.errors import Lf3pmError
from lf3pm.grid import Space


@dataclass(frozen=True)
class MapCase:
    """One map of a study, how its SOLM is built and where its pairs are drawn.

    ``source``: ``scene:NAME`` (a procedural scene, ``scene_seed``, ``scene_params``) or a
    map file: a path, or a name in the shared data folder. ``zones``: {"start": ZONE,
    "goal": ZONE} for files (scenes bring their own; a case's zone replaces the
    scene's of that name), each a box (xmin, ymin, xmax, ymax) or a polygon ((x, y),
    ...). ``yaw_ranges``: {"start" or "goal": (lo, hi)} in radians (SE(2) only): the
    yaw of a pose drawn in that zone, uniform in [lo, hi]; without one a pair's start
    and goal face from start to goal. Pairs are at least ``min_distance`` m apart; with
    ``both_ways`` every other pair runs goal to start. ``r_safe``: the robots' clearance
    beyond the SOLM's robot radius. ``space`` may be given by its name. Cases are read
    from YAML by lf3pm.experiments.benefit.case_file.
    """

    name: str
    source: str
    sensor: str
    space: Space
    res: float
    pairs: int = 0
    robots: tuple = ("omni", "diff")
    yaw_bins: int = DEFAULTS.solm.yaw_bins
    yaw_reuse: bool = DEFAULTS.solm.yaw_reuse
    ray_stride: int = DEFAULTS.solm.ray_stride
    scene_params: dict = field(default_factory=dict)
    scene_seed: int = 0
    bounds: tuple | None = None
    zones: dict | None = None
    min_distance: float = 10.0
    both_ways: bool = False
    r_safe: float = DEFAULTS.robot.r_safe
    yaw_ranges: dict | None = None

    def __post_init__(self):
        object.__setattr__(self, "space", Space(self.space))
        object.__setattr__(self, "robots", tuple(self.robots))
        if self.bounds is not None:
            object.__setattr__(self, "bounds", tuple(self.bounds))
        if self.zones is not None:
            object.__setattr__(self, "zones", {end: _zone_tuple(zone) for end, zone in self.zones.items()})
        if self.yaw_ranges is not None:
            object.__setattr__(self, "yaw_ranges", {end: tuple(r) for end, r in self.yaw_ranges.items()})


def is_polygon(zone) -> bool:
    """Whether ``zone`` is a polygon ((x, y), ...) rather than a box (xmin, ymin, xmax, ymax)."""
    return len(zone) > 0 and isinstance(zone[0], (tuple, list))


def _zone_tuple(zone) -> tuple:
    return tuple(tuple(vertex) for vertex in zone) if is_polygon(zone) else tuple(zone)


def zone_box(zone) -> tuple:
    """The box (xmin, ymin, xmax, ymax) around ``zone`` (a box: itself)."""
    if not is_polygon(zone):
        return tuple(zone)
    xs, ys = [v[0] for v in zone], [v[1] for v in zone]
    return (min(xs), min(ys), max(xs), max(ys))


def in_polygon(polygon, x: float, y: float) -> bool:
    """Whether (x, y) lies inside ``polygon`` ((x, y), ...; even-odd rule)."""
    inside = False
    n = len(polygon)
    for i in range(n):
        (x0, y0), (x1, y1) = polygon[i], polygon[(i + 1) % n]
        if (y0 > y) != (y1 > y) and x < x0 + (y - y0) * (x1 - x0) / (y1 - y0):
            inside = not inside
    return inside


def case_source(case: MapCase):
    """(what the case's map is read from: its scene's points or its file, zones)."""
    if case.source.startswith("scene:"):
        from lf3pm.scenes import build_scene

        scene = build_scene(case.source.split(":", 1)[1], seed=case.scene_seed, **case.scene_params)
        zones = {name: tuple(zone) for name, zone in scene.zones.items()}
        return scene.points, {**zones, **(case.zones or {})}
    from lf3pm.experiments.data import shared_data_dir

    if case.zones is None or not {"start", "goal"} <= set(case.zones):
        raise Lf3pmError(f"map case {case.name}: a map file needs its start and goal zones")
    return shared_data_dir() / case.source, dict(case.zones)


def load_case_map(case: MapCase):
    """(Map, zones) of a case; the same in the main process and in every worker."""
    from lf3pm.map import load_map

    source, zones = case_source(case)
    return load_map(source), zones


def build_case_solm(case: MapCase, path: Path, world=None) -> Path:
    """Builds (or resumes) the case's SOLM into ``path`` (seed 0); ``world`` reuses a loaded map."""
    from lf3pm.sensors import get_sensor
    from lf3pm.solm import build_solm, make_grid

    if world is None:
        world, _ = load_case_map(case)
    grid = make_grid(world, case.space, case.res, bounds=case.bounds, yaw_bins=case.yaw_bins)
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    build_solm(world, get_sensor(case.sensor), grid, path, seed=0, yaw_reuse=case.yaw_reuse, ray_stride=case.ray_stride)
    return path
