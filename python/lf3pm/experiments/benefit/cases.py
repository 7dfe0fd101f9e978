"""The benefit study's maps: procedural scenes built for the question and two real maps,
each a :class:`~lf3pm.experiments.map_cases.MapCase`."""

from __future__ import annotations

from dataclasses import replace

from lf3pm.experiments.map_cases import MapCase
from lf3pm.grid import Space
from lf3pm.scenes.gobi import REDUCED as REDUCED_SCENE

#: Zones of the two real maps (single scans in their sensor frames), where their ground is
#: sampled densely enough to plan on (docs/benefit.md): the room scan's free floor spans
#: about 5 m, the street sweep's rings of ground need 1.5 m cells.
_ROOM_ZONES = {"start": (1.3, -0.6, 2.3, 0.6), "goal": (4.8, 0.6, 5.9, 1.9)}
_STREET_ZONES = {"start": (-25.0, -25.0, -15.0, -15.0), "goal": (0.0, -25.0, 15.0, -15.0)}

CASES = (
    MapCase(
        "tunnel",
        "scene:tunnel",
        "vlp16",
        Space.R2,
        0.5,
        8,
        ray_stride=4,
        scene_params={"length": 40.0},
        both_ways=True,
        min_distance=30.0,
    ),
    MapCase(
        "orientation", "scene:orientation", "mid70", Space.SE2, 1.0, 8, yaw_reuse=True, ray_stride=4, min_distance=20.0
    ),
    MapCase(
        "gobi",
        "scene:gobi",
        "mid70",
        Space.SE2,
        1.0,
        8,
        yaw_reuse=True,
        ray_stride=2,
        scene_params=REDUCED_SCENE,
        bounds=(-15.0, -30.0, 55.0, 30.0),
        zones={"start": (-8.0, -8.0, 8.0, 8.0), "goal": (30.0, -20.0, 45.0, 20.0)},
        min_distance=25.0,
    ),
    MapCase("houses", "scene:houses", "vlp16", Space.R2, 0.5, 8, ray_stride=4, both_ways=True, min_distance=20.0),
    # The room's halves join through gaps that leave the body 0.28 m on each side.
    MapCase(
        "boxes", "scene:boxes", "vlp16", Space.R2, 0.25, 6, ray_stride=4, both_ways=True, min_distance=8.0, r_safe=0.2
    ),
    MapCase(
        "street",
        "outdoor_urban64_2021-10-26-16-21-29-468.pcd",
        "vlp16",
        Space.R2,
        1.5,
        6,
        ray_stride=4,
        bounds=(-30.0, -30.0, 30.0, 30.0),
        zones=_STREET_ZONES,
        both_ways=True,
        min_distance=15.0,
    ),
    # Its start and goal zones join only with 0.1-0.15 m to spare beyond the body.
    MapCase(
        "room",
        "indoor_pcl_room_scan1.pcd",
        "vlp16",
        Space.R2,
        0.25,
        4,
        ray_stride=4,
        bounds=(-3.0, -2.5, 8.5, 3.5),
        zones=_ROOM_ZONES,
        both_ways=True,
        min_distance=2.5,
        r_safe=0.1,
    ),
    # Appended, not inserted: a case's pairs are drawn from its index (pair seed, index).
    MapCase(
        "corridor",
        "scene:corridor",
        "mid70",
        Space.SE2,
        0.5,
        8,
        yaw_reuse=True,
        ray_stride=4,
        both_ways=True,
        min_distance=30.0,
    ),
    MapCase("field", "scene:field", "mid70", Space.SE2, 1.0, 8, yaw_reuse=True, ray_stride=4, min_distance=60.0),
)

#: `--quick`: two small maps, one pair each, one seed (the test suite's run).
QUICK = (
    replace(CASES[0], pairs=1, scene_params={"length": 20.0, "pillars": 8}, min_distance=20.0),
    replace(CASES[1], pairs=1, res=2.0, yaw_bins=12),
)
