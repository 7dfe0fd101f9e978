"""One typed configuration for every parameter a user sets (pydantic, as kiss-icp's).

Each section maps one to one onto a C++ parameter struct of the core and reads its
defaults from it, so that a default is written once, in C++ (``MapParams``,
``ScanParams``, ``EvalParams``, ``RobotLimits``, ``QuadrotorParams``, ``QuadrotorLimits``;
the sections with no C++ struct write theirs here). Every value is validated once,
here: finite, in range, an integer where one is meant. The library's entry points (``load_map``, ``evaluate``, ``mde``,
``make_grid``, ``build_solm``, ``replay``, ``Robot``) validate their arguments through
these sections, and the CLI builds a :class:`Config` from ``--config FILE.yaml``
overridden by its flags. Checks that need the data (bounds inside the map, a grid's
size, a disturbance against the map's extent) stay where the data are.

A YAML file holds any subset of the sections (see config/*.yaml)::

    sensor: mid70
    scan: {noise: 0.01, seed: 3}
    solm: {space: se2, res: 0.25}
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any, Literal

import yaml
from pydantic import BaseModel, ConfigDict, Field, ValidationError, model_validator

from lf3pm import _core
from lf3pm.errors import Lf3pmError
from lf3pm.grid import Space
from lf3pm.limits import clip, excerpt, load_yaml, read_text_file

_MAP = _core.MapParams()
_SCAN = _core.ScanParams()
_EVAL = _core.EvalParams()
_LIMITS = _core.RobotLimits()
_QUADROTOR = _core.QuadrotorParams()
_FLIGHT_LIMITS = _core.QuadrotorLimits()

#: The core's noise streams take 64-bit seeds (Python's and numpy's seed sequences take
#: any non-negative int; 2^63 - 1 keeps a seed an int64 in JSON and Zarr attributes).
MAX_SEED = 2**63 - 1
#: OpenMP aborts the process when asked for a negative or huge team of threads.
MAX_THREADS = 1024

#: The SOLM's state spaces (lf3pm.solm.grid) and the replay's state estimators (the names
#: YAML and the CLI take; lf3pm.replays.methods.METHODS holds the methods by these names).
SPACES = tuple(space.value for space in Space)
REPLAY_METHODS = ("localization", "lio", "odometry")

#: The drives `lf3pm experiment odometries` replays (lf3pm.experiments.odometries.DRIVES).
ODOMETRY_DRIVES = ("boxes", "houses", "gobi", "tunnel", "hall", "hall3")

#: Robot kinds (lf3pm.trajectory.robots.Robot) and the SOLM channels a plan can be guided by.
ROBOT_KINDS = ("omni", "diff", "car")
#: Where a quadrotor carries its LiDAR (lf3pm.flight.mounts.MOUNTS holds them by these names).
SENSOR_MOUNTS = ("top", "down20", "side")
#: What the planner makes of a SOLM's unknown cells (no map under them; planner/esdf.py).
UNKNOWN_POLICIES = ("obstacle", "free")
COST_CHANNELS = ("q_n", "q_min", "q_max", "step_norm", "q_n_q_min", "none")
#: Cost channels made of SOLM channels: each part relative to its own map median, the larger
#: taken per cell (planner/cost_map.py).
COMPOSITE_CHANNELS = {"q_n_q_min": ("q_n", "q_min")}
#: The smallest speed, yaw rate or acceleration limit a robot takes (m/s, rad/s, m/s^2,
#: rad/s^2): slower is no robot, and a 10 m plan at 1e-9 m/s would be 300 years of 100 Hz samples.
MIN_LIMIT = 1e-3
#: The largest (same units): no ground robot drives 100 m/s (360 km/h), turns 100 rad/s
#: (16 turns a second) or accelerates at 10 g; with 1e12 the optimiser's trajectory came
#: out 6e6 s long.
MAX_LIMIT = 100.0

#: The largest k-NN grid voxel (m): FAST-LIO's farthest neighbour is sqrt(5) m, and a larger
#: voxel only crowds each cell (one evaluate on the boxes room: 2 s at its own 0.16 m, 25 s
#: at 10 m, 49 s at 20 m; at 1e6 m the search returned wrong planes, at 1e12 m none).
MAX_CELL_SIZE = 10.0
#: The longest trajectory a replay takes (s): an hour is 36,000 scans at 10 Hz (hours of
#: LIO per seed) and its motion's ground profile 360,000 knots at 100 Hz (90 MB); a day of
#: them (from a CSV's last time stamp: 1e7 s) filled 12 GB without end.
MAX_TRAJECTORY_SECONDS = 3600.0
#: The coarsest SOLM cell (m): wider than any LiDAR's range (the presets reach 260 m), so
#: a larger --res is a typo; make_grid also refuses a cell wider than the grid's extent.
MAX_RES = 1000.0
#: The most poses a SOLM may hold even with a raised --max-cells: its six float32
#: channels then take 24 GB, what a large workstation can still hold for the planner,
#: and a build of that many poses takes days on a cluster (docs/scale.md).
MAX_CELLS_CEILING = 1_000_000_000
#: The largest SOLM tile edge (cells): a tile is a chunk, held whole in memory by every
#: read and write.
MAX_TILE = 1024

#: Sensor height above the local ground (m) of a ground robot: a LiDAR on a small
#: wheeled base. SOLM grids and the replay's motion take it by default.
DEFAULT_HEIGHT = 1.0


class ConfigError(Lf3pmError):
    """A parameter out of range, of the wrong type or unknown."""


class Section(BaseModel):
    """A group of parameters: unknown names, NaN and infinities are refused."""

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False, frozen=True)


class MapConfig(Section):
    """Map indexing and FAST-LIO association (C++ MapParams)."""

    voxel: float | None = Field(None, gt=0, description="Voxel-downsample the map first (m; none: off).")
    cell_size: float = Field(
        _MAP.cell_size, ge=0, le=MAX_CELL_SIZE, description="k-NN grid voxel (m; 0: from the point spacing)."
    )
    knn: int = Field(_MAP.knn, ge=3, le=64, description="Neighbours per association plane (FAST-LIO NUM_MATCH_POINTS).")
    plane_threshold: float = Field(
        _MAP.plane_threshold, gt=0, description="Plane validity: every neighbour within this of the plane (m)."
    )
    max_neighbor_distance: float = Field(
        _MAP.max_neighbor_distance, gt=0, description="Farthest allowed k-th neighbour (m; FAST-LIO: sqrt 5)."
    )

    def core(self, threads: int = 0) -> _core.MapParams:
        """The C++ struct."""
        return core_struct(
            _core.MapParams(),
            cell_size=self.cell_size,
            knn=self.knn,
            plane_threshold=self.plane_threshold,
            max_neighbor_distance=self.max_neighbor_distance,
            threads=threads,
        )

    def association_params(self) -> dict:
        """What a metric depends on, for result provenance."""
        return {
            "knn": self.knn,
            "plane_threshold": self.plane_threshold,
            "max_neighbor_distance": self.max_neighbor_distance,
        }


class ScanConfig(Section):
    """Scan simulation (C++ ScanParams; the ranges come from the sensor)."""

    noise: float | None = Field(None, ge=0, le=10.0, description="Range noise sigma (m; none: the sensor's).")
    seed: int = Field(_SCAN.seed, ge=0, le=MAX_SEED, description="Seed of the range noise.")
    scan_voxel: float = Field(
        _SCAN.scan_voxel, ge=0, le=100.0, description="Scan downsampling voxel (m; FAST-LIO filter_size_surf; 0: off)."
    )
    threads: int = Field(_SCAN.threads, ge=0, le=MAX_THREADS, description="Worker threads (0 = all cores).")
    clearance: float = Field(
        0.1, ge=0, le=100, description="Free space a pose needs around the sensor: no map point closer (m)."
    )

    def noise_for(self, sensor) -> float:
        """The range noise sigma: this section's, else the sensor's."""
        return float(sensor.range_noise_sigma if self.noise is None else self.noise)

    def core(self, sensor, stream: int = 0) -> _core.ScanParams:
        """The C++ struct for ``sensor``'s ranges."""
        return scan_params(
            sensor.min_range,
            sensor.max_range,
            noise=self.noise_for(sensor),
            seed=self.seed,
            stream=stream,
            scan_voxel=self.scan_voxel,
            threads=self.threads,
            returns=sensor.returns,
        )


class MetricConfig(Section):
    """The metric's state space, association and weight (C++ EvalParams, MetricWeights)."""

    dof: Literal[3, 6] = Field(_EVAL.dof, description="6 for SE(3), 3 for (x, y, yaw).")
    association: Literal["knn", "surfel"] = Field(
        _EVAL.association.name,
        description="'knn' (FAST-LIO's k-NN plane at each hit) or 'surfel' "
        "(the hit map point's precomputed plane; faster).",
    )
    w1: float = Field(_EVAL.weights.w1, gt=0, lt=1, description="Metric weight w1 (w2 = 1 - w1).")

    def core(self, scan: _core.ScanParams, ray_weight: float = 1.0) -> _core.EvalParams:
        """The C++ struct around ``scan``."""
        params = _core.EvalParams()
        params.scan = scan
        params.dof = self.dof
        params.association = getattr(_core.Association, self.association)
        params.weights.w1 = self.w1
        params.ray_weight = float(ray_weight)
        return params


class PredictionConfig(Section):
    """Where the predicted localization error comes from (lf3pm.calibration)."""

    calibration: str | None = Field(
        None,
        min_length=1,
        description="A localization-error fit (JSON) from `lf3pm audit --calibrate` on your own run, used "
        "instead of the packaged one (none: the packaged one).",
    )


class MdeConfig(Section):
    """MDE: registration from disturbed starts."""

    trials: int = Field(20, ge=1, le=100_000, description="Disturbed registration starts.")
    sigma_t: float = Field(0.1, ge=0, description="Start disturbance, translation sigma per axis (m).")
    sigma_r: float = Field(2.0, ge=0, le=180, description="Start disturbance, rotation sigma per axis (deg).")
    max_correspondence_distance: float = Field(1.0, gt=0, description="Registration's correspondence cutoff (m).")
    max_iterations: int = Field(50, ge=1, le=10_000, description="Registration's iteration limit.")


class SolmConfig(Section):
    """The SOLM grid and build."""

    space: Space = Field(
        Space.R2, description="r2 (x, y), se2 (x, y, yaw), r3 (x, y, z) or r3yaw (x, y, z, yaw: quadrotors)."
    )
    res: float = Field(0.5, gt=0, le=MAX_RES, description="Cell size (m).")
    yaw_bins: int = Field(36, ge=1, le=3600, description="Yaw bins (se2, r3yaw).")
    yaw_reuse: bool = Field(
        False, description="se2: one scan per yaw sector, summed per bin (faster, approximate; docs/solm.md)."
    )
    ray_stride: int = Field(
        1,
        ge=1,
        le=1000,
        description="Cast every K-th azimuth column and scale the Gram "
        "(about K times faster, approximate; docs/solm.md).",
    )
    height: float = Field(
        DEFAULT_HEIGHT, gt=0, le=100, description="Sensor height above the local ground (m; r2, se2)."
    )
    bounds: tuple[float, float, float, float] | None = Field(
        None, description="XMIN YMIN XMAX YMAX (m; none: the map's extent)."
    )
    robot_radius: float = Field(0.3, ge=0, le=100, description="Robot radius for the obstacle mask (m).")
    floor_clearance: float = Field(
        0.2, ge=0, le=100, description="Height above the ground from which a point blocks a ground robot's cell (m)."
    )
    max_cells: int = Field(10_000_000, ge=1, le=MAX_CELLS_CEILING, description="Refuse a grid of more poses than this.")
    crop_above: int = Field(
        20_000_000,
        ge=1,
        description="Build maps of more points than this tile by tile, each tile on its crop (docs/scale.md).",
    )
    tile: int = Field(
        32,
        ge=1,
        le=MAX_TILE,
        description="Tile (and Zarr chunk) edge in cells; a tile holds every yaw bin or z level.",
    )
    occupancy_res: float = Field(
        0.1,
        gt=0,
        le=MAX_RES,
        description="Target edge of the occupancy layer's cells (m): a thin obstacle's position is known "
        "to within it (ground robots; the SOLM's cells split into k x k, solm/occupancy.py).",
    )
    max_occupancy_cells: int = Field(
        1 << 20,
        ge=1,
        le=MAX_CELLS_CEILING,
        description="Most occupancy cells (the planner's ESDF over them builds in ~3 s and 0.5 GB); "
        "larger grids get coarser ones, down to the SOLM's own.",
    )


class RobotConfig(Section):
    """A ground robot's kind and limits (SI units; C++ RobotLimits).

    ``kind``: ``omni`` (holonomic: body-frame longitudinal and lateral speed limits),
    ``diff`` (differential drive: no lateral motion) or ``car`` (diff plus a minimum
    turning radius ``min_turn_radius``, |omega| <= |v_lon| / R). ``vmax_norm`` (omni
    only) also limits the speed |v| itself, by default to max(vmax_lon, vmax_lat)
    (``inf``: no such limit): with only the body-frame limits an omni robot is fastest
    moving diagonally (sqrt(vmax_lon^2 + vmax_lat^2)), which a time-weighted planner
    exploits by yawing 45 degrees off its path. ``r_safe`` is the clearance the
    trajectory keeps from obstacles (ESDF >= r_safe) beyond the SOLM's robot radius.
    ``amax_lon`` and ``amax_lat`` limit the acceleration in the body frame (diff and
    car: tangential and centripetal), ``alpha_max`` the yaw acceleration, so that a
    real base can track the trajectory.
    """

    kind: Literal[ROBOT_KINDS] = Field("omni", description="omni, diff (differential drive) or car.")
    vmax_lon: float = Field(_LIMITS.vmax_lon, ge=MIN_LIMIT, le=MAX_LIMIT, description="Longitudinal speed limit (m/s).")
    vmax_lat: float = Field(
        _LIMITS.vmax_lat, ge=MIN_LIMIT, le=MAX_LIMIT, description="Lateral speed limit (m/s; omni)."
    )
    wmax: float = Field(_LIMITS.wmax, ge=MIN_LIMIT, le=MAX_LIMIT, description="Yaw rate limit (rad/s).")
    amax_lon: float = Field(
        _LIMITS.amax_lon,
        ge=MIN_LIMIT,
        le=MAX_LIMIT,
        description="Longitudinal (tangential) acceleration limit (m/s^2).",
    )
    amax_lat: float = Field(
        _LIMITS.amax_lat, ge=MIN_LIMIT, le=MAX_LIMIT, description="Lateral (centripetal) acceleration limit (m/s^2)."
    )
    alpha_max: float = Field(
        _LIMITS.alpha_max, ge=MIN_LIMIT, le=MAX_LIMIT, description="Yaw acceleration limit (rad/s^2)."
    )
    min_turn_radius: float = Field(_LIMITS.min_turn_radius, ge=0, description="Minimum turning radius (m; car).")
    r_safe: float = Field(_LIMITS.r_safe, ge=0, description="Clearance beyond the SOLM's robot radius (m).")
    vmax_norm: float | None = Field(
        None,
        gt=0,
        allow_inf_nan=True,
        description="Speed-norm limit (m/s; omni; inf: none; default: the larger of vmax_lon and vmax_lat).",
    )

    @model_validator(mode="after")
    def _kind_limits(self):
        if self.vmax_norm is not None:
            if math.isnan(self.vmax_norm):
                raise ValueError("vmax_norm must be a positive number (inf: none), got nan")
            if self.kind != "omni":
                raise ValueError(f"a speed-norm limit applies to omni robots only, not {self.kind!r}")
        elif self.kind == "omni":
            # A base's wheels limit its speed, not only its body-frame components: with the
            # box alone a time-weighted plan yaws 45 degrees off its path to go sqrt(2) faster.
            object.__setattr__(self, "vmax_norm", float(max(self.vmax_lon, self.vmax_lat)))
        if self.kind != "car" and self.min_turn_radius > 0:
            raise ValueError(f"a minimum turning radius applies to car robots only, not {self.kind!r}")
        return self


class QuadrotorConfig(Section):
    """A quadrotor's mass, drag and flight limits (SI units, angles in radians; C++
    QuadrotorParams and QuadrotorLimits) and where it carries its LiDAR (lf3pm.flight).

    The thrust limits must hold the hover thrust, mass x gravity, between them.
    ``mount``: ``top`` (a Mid-360 on top, level), ``down20`` (a forward LiDAR pitched down
    20 degrees, as EAROL's), ``side`` (a VLP-16 on its side, its spin axis along the body's
    x axis); docs/flight.md.
    """

    mass: float = Field(_QUADROTOR.mass, ge=0.01, le=1000.0, description="Mass (kg).")
    drag_h: float = Field(_QUADROTOR.drag_h, ge=0, le=MAX_LIMIT, description="Horizontal linear drag (N per m/s).")
    drag_v: float = Field(_QUADROTOR.drag_v, ge=0, le=MAX_LIMIT, description="Vertical linear drag (N per m/s).")
    vmax: float = Field(_FLIGHT_LIMITS.vmax, ge=MIN_LIMIT, le=MAX_LIMIT, description="Speed limit (m/s).")
    omega_max: float = Field(
        _FLIGHT_LIMITS.omega_max, ge=MIN_LIMIT, le=MAX_LIMIT, description="Body-rate limit (rad/s)."
    )
    tilt_max: float = Field(
        _FLIGHT_LIMITS.tilt_max, ge=MIN_LIMIT, le=1.5, description="Tilt limit from the vertical (rad)."
    )
    thrust_min: float = Field(_FLIGHT_LIMITS.thrust_min, ge=0, description="Least thrust (N).")
    thrust_max: float = Field(_FLIGHT_LIMITS.thrust_max, gt=0, description="Largest thrust (N).")
    mount: Literal[SENSOR_MOUNTS] = Field("top", description="Where the LiDAR sits: top, down20 or side.")

    @model_validator(mode="after")
    def _hover(self):
        hover = self.mass * _QUADROTOR.gravity
        if not self.thrust_min < hover < self.thrust_max:
            raise ValueError(
                f"the hover thrust {hover:.3g} N (mass x gravity) must lie between thrust_min "
                f"({self.thrust_min:g}) and thrust_max ({self.thrust_max:g})"
            )
        return self

    def params(self) -> _core.QuadrotorParams:
        """The C++ parameters."""
        return core_struct(_core.QuadrotorParams(), mass=self.mass, drag_h=self.drag_h, drag_v=self.drag_v)

    def limits(self) -> _core.QuadrotorLimits:
        """The C++ limits."""
        return core_struct(
            _core.QuadrotorLimits(),
            vmax=self.vmax,
            omega_max=self.omega_max,
            tilt_max=self.tilt_max,
            thrust_min=self.thrust_min,
            thrust_max=self.thrust_max,
        )


class GuidanceConfig(Section):
    """How a SOLM channel guides the planner: an edge through cells of cost c (the channel
    over its median, to ``power``) costs its length times (1 + ``weight`` c), and a turn
    of the sensor the arc a point ``turn_radius`` from its axis travels. q_n, power 1:
    localization error grows about in proportion to q_n, so the cost is proportional to
    the predicted error. The measurements behind the defaults: docs/design.md, "Default
    guidance"; docs/benefit.md, docs/lio.md.
    """

    metric: Literal[COST_CHANNELS] = Field(
        "q_n",
        description="SOLM channel guiding the plan: q_n, q_min, q_max, step_norm, q_n_q_min (the worse of q_n "
        "and q_min per cell) or none (shortest path).",
    )
    weight: float = Field(
        3.0,
        ge=0,
        le=1e6,
        description="lambda: an edge through cells of cost c costs length (1 + lambda c); a median cell has c = 1 "
        "(docs/benefit.md).",
    )
    power: float = Field(
        1.0,
        gt=0,
        le=10,
        description="Exponent applied to the channel (over its median) before the weight (docs/benefit.md).",
    )
    turn_radius: float = Field(
        2.0,
        ge=0,
        le=100,
        description="A turn of the sensor costs the arc a point this far from its axis travels (m per rad; "
        "docs/benefit.md, docs/lio.md).",
    )


class PlannerConfig(Section):
    """The planner's front end on a SOLM (lf3pm.planner.Planner)."""

    unknown: Literal[UNKNOWN_POLICIES] = Field(
        "obstacle",
        description="A SOLM's unknown cells (no map under them): obstacle (kept away from like one, not "
        "traversable) or free ground.",
    )
    clearance_step: float = Field(
        0.1,
        gt=0,
        le=10,
        description="Most spacing of the clearance samples along a front-end path (m; quarter SOLM cells where "
        "finer): beside a pole 0.3 m + r_safe away the field dips below two samples by under 1 cm, which "
        "the optimiser's margin covers.",
    )


class GroundConfig(Section):
    """The smooth ground a replayed ground robot drives on (lf3pm.replays.ground)."""

    cell: float = Field(
        0.25,
        gt=0,
        le=MAX_RES,
        description="Column grid (m): several map points per column for maps sampled every 5-10 cm.",
    )
    smoothing: float = Field(
        0.5, gt=0, le=100, description="Gaussian sigma (m): half the footprint of a small wheeled base (about 1 m)."
    )
    max_step: float = Field(
        0.25,
        gt=0,
        le=100,
        description="Largest height change between neighbouring columns that is still ground (m): 0.25 m over "
        "a 0.25 m cell is a 45 degree slope, steeper than a wheeled robot drives; a box side or a wall "
        "jumps by more.",
    )


class ReplayConfig(Section):
    """Replays of a trajectory through a state estimator."""

    method: Literal[REPLAY_METHODS] = Field(
        "localization", description="localization (prior map), lio or odometry (KISS-ICP)."
    )
    seeds: int = Field(1, ge=1, le=10_000, description="Runs seeds SEED .. SEED+N-1 and reports each and the median.")
    height: float = Field(DEFAULT_HEIGHT, gt=0, le=100, description="Sensor height above the smoothed ground (m).")
    rate: float = Field(10.0, gt=0, le=1000, description="Scans per second.")
    imu_rate: float = Field(200.0, gt=0, le=100_000, description="The lio method's IMU samples per second.")
    imu_noise: bool = Field(True, description="The lio method's IMU noise (false: exact samples).")
    imu_preset: str | None = Field(
        None, min_length=1, description="The lio method's IMU model (lf3pm.replays.imu.PRESETS; none: bmi088)."
    )
    odometry: str = Field(
        "auto",
        min_length=1,
        description="The lio method's odometry: genz (GenZ-LIO), dlio (DLIO, from evalio), liosam "
        "(LIO-SAM, from evalio; spinning sensors only), one a plugin registers, or auto (dlio for a "
        "spinning sensor, genz for a non-repetitive one: docs/lio.md).",
    )
    rest: float = Field(
        2.0,
        ge=0,
        le=MAX_TRAJECTORY_SECONDS,
        description="Seconds the sensor stands still at the first pose before a lio replay's trajectory, "
        "for the odometry to initialise (scored from the trajectory's start; docs/lio.md).",
    )
    rest_window: float = Field(
        0.5,
        gt=0,
        le=MAX_TRAJECTORY_SECONDS,
        description="The last seconds of the rest over which the estimate's speed is measured (steady or not).",
    )
    rest_speed_limit: float = Field(
        0.05,
        gt=0,
        le=MAX_LIMIT,
        description="Fastest a steady rest's estimate moves over its last rest_window s (m/s): faster hands "
        "the trajectory a velocity error (0.05 m/s is 5 cm after a second, more than a good LIO run's "
        'APE), so its APE measures the odometry\'s start (docs/lio.md, "A still sensor").',
    )
    odometries: dict[str, dict[str, Any]] = Field(
        {},
        description="Each odometry's settings by its name (lf3pm config lists them, with lf3pm's defaults): "
        "what is given here goes over lf3pm's, validated by the odometry's settings section "
        "(lf3pm.replays.registry).",
    )


class LocalizationConfig(Section):
    """The localization replay: wheel odometry predicting small_gicp registrations to the
    prior map, degenerate directions kept at the prediction (docs/replay.md says why)."""

    scale_error: float = Field(
        0.02, gt=-1, le=10, description="Wheel odometry: fractional error of the travelled distance."
    )
    yaw_noise: float = Field(
        0.01, ge=0, le=10, description="Wheel odometry: density of the heading's random walk (rad/sqrt(s))."
    )
    scan_voxel: float = Field(
        0.25, ge=0, le=100, description="Scan downsampling voxel before registration (m; 0: off)."
    )
    degenerate_std: float = Field(
        0.01,
        gt=0,
        le=100,
        description="Largest deviation range noise may leave in a direction that counts as constrained (m).",
    )
    remap: bool = Field(True, description="Keep the prediction along degenerate directions (Zhang et al. 2016).")
    max_correspondence_distance: float = Field(
        1.0, gt=0, le=1000, description="Registration's correspondence cutoff (m)."
    )
    max_iterations: int = Field(30, ge=1, le=10_000, description="Registration's iteration limit.")
    min_points: int = Field(100, ge=1, description="Fewest points a registration may use (fewer: the prediction).")
    registration_threads: int = Field(
        1, ge=1, le=MAX_THREADS, description="Registration threads (1: bit-for-bit reproducible)."
    )


class KissIcpConfig(Section):
    """The odometry replay's KISS-ICP."""

    voxel_size: float = Field(
        1.0, gt=0, le=100, description="Local map voxel (m; KISS-ICP's own choice for outdoor 100 m LiDARs)."
    )
    min_points: int = Field(100, ge=1, description="Scans with fewer hits are not given to KISS-ICP.")
    deskew: bool = Field(True, description="KISS-ICP deskews each scan from its returns' firing times.")


class RunConfig(Section):
    """A recorded run (lf3pm.runs, docs/runs.md): where it is, its topics, the LiDAR's
    mounting on the body whose poses the run holds, and the LiDAR's clock."""

    source: str | None = Field(
        None,
        min_length=1,
        description="The run: a folder of scans with a poses file, a ROS 1 .bag or a ROS 2 bag folder.",
    )
    scans_topic: str | None = Field(
        None,
        min_length=1,
        description="The bag's PointCloud2 or Livox CustomMsg topic (none: the one topic of such a type).",
    )
    imu_topic: str | None = Field(
        None, min_length=1, description="The bag's sensor_msgs/Imu topic (none: the one such topic, if any)."
    )
    poses_topic: str | None = Field(
        None,
        min_length=1,
        description="The bag's reference poses: nav_msgs/Odometry, geometry_msgs/PoseStamped or nav_msgs/Path "
        "(none: the one topic of those types, if any).",
    )
    lidar_translation: tuple[float, float, float] = Field(
        (0.0, 0.0, 0.0), description="The LiDAR's position in the body frame (m): body = R lidar + t."
    )
    lidar_quaternion: tuple[float, float, float, float] | None = Field(
        None, description="The LiDAR-to-body rotation as a unit quaternion x y z w (none: lidar_rpy)."
    )
    lidar_rpy: tuple[float, float, float] | None = Field(
        None,
        description="The LiDAR-to-body rotation as roll, pitch, yaw in degrees, R = Rz(yaw) Ry(pitch) Rx(roll) "
        "(none with no lidar_quaternion: the identity).",
    )
    lidar_time_offset: float = Field(
        0.0, ge=-1e6, le=1e6, description="Added to each LiDAR stamp to put it on the poses' and IMU's clock (s)."
    )
    max_pose_gap: float = Field(
        1.0,
        gt=0,
        le=1e6,
        description="Longest time between two reference poses across which a scan's pose is interpolated (s); "
        "a scan in a longer gap has no pose.",
    )
    # At a walking pace several metres of the run either side: a scan's own surfaces are
    # then in its map only as other scans saw them from elsewhere.
    exclude_window: float = Field(
        5.0,
        ge=0,
        le=1e6,
        description="A map from the run itself (lf3pm audit --map self): the scans within this time of an "
        "audited scan stay out of its map (s; 0: the scan itself alone).",
    )

    @model_validator(mode="after")
    def _one_rotation(self):
        if self.lidar_quaternion is not None and self.lidar_rpy is not None:
            raise ValueError("give lidar_quaternion or lidar_rpy, not both")
        if self.lidar_quaternion is not None and abs(math.hypot(*self.lidar_quaternion) - 1.0) > 1e-3:
            raise ValueError(f"lidar_quaternion's norm is {math.hypot(*self.lidar_quaternion):.6g}, not 1")
        return self


def _seed(what: str):
    return Field(0, ge=0, le=MAX_SEED, description=f"Seed of {what}.")


class Table1Config(Section):
    """`lf3pm experiment table1` (the disturbances: the mde section's)."""

    poses: int = Field(8, ge=1, le=100_000, description="Poses per scene (reference position at 4 yaws, then random).")
    trials: int = Field(10, ge=1, le=100_000, description="MDE trials per pose.")
    seed: int = _seed("the scenes, poses, noise and disturbances")


class CorrelationConfig(Section):
    """`lf3pm experiment correlation`."""

    poses_per_map: int = Field(40, ge=3, le=100_000, description="Random free poses per map (scenes and real maps).")
    trials: int = Field(5, ge=1, le=100_000, description="MDE trials per pose.")
    bootstrap: int = Field(1000, ge=1, le=1_000_000, description="Bootstrap resamples for the confidence intervals.")
    seed: int = _seed("the scenes, poses, noise and disturbances")


class BenefitConfig(Section):
    """`lf3pm experiment benefit`."""

    seeds: int = Field(3, ge=1, le=10_000, description="Replay seeds per plan and method.")
    workers: int = Field(2, ge=1, le=MAX_THREADS, description="Replay processes.")
    pair_seed: int = _seed("the start/goal pairs")
    lio: Literal["all", "default"] = Field(
        "all",
        description="Plans the LIO replays too: all, or default (the default's and the unguided one; a shorter run).",
    )
    odometry: str = Field(
        "auto",
        min_length=1,
        description="The LIO replays' odometry, as replay.odometry (liosam: on the maps of a spinning "
        "sensor, auto's choice on the others); each odometry keeps its own replays.",
    )


class GobiConfig(Section):
    """`lf3pm experiment gobi` (the rest of its setup: experiments/gobi.py)."""

    seed: int = _seed("the scene, the noise and the disturbances")
    seeds: int | None = Field(
        None, ge=1, le=10_000, description="Replay seeds per plan and method (none: the setup's)."
    )


class OdometriesConfig(Section):
    """`lf3pm experiment odometries` (its drives: lf3pm.experiments.odometries)."""

    scenes: tuple[Literal[ODOMETRY_DRIVES], ...] = Field(
        ("boxes", "houses", "gobi", "tunnel"),
        min_length=1,
        description="Drives: boxes (a figure of eight), houses, gobi (its town), tunnel, hall, hall3 (comma "
        "separated or repeated).",
    )
    sensors: tuple[str, ...] = Field(
        ("vlp16", "mid70"), min_length=1, description="Sensor presets or YAML files (comma separated or repeated)."
    )
    odometries: tuple[str, ...] | None = Field(
        None,
        min_length=1,
        description="The odometries compared (comma separated or repeated; none: every registered one).",
    )
    seeds: int = Field(1, ge=0, le=10_000, description="Noisy runs on seeds 0 .. N-1 beside the noise-free one.")
    seconds: float | None = Field(
        None,
        gt=0,
        le=MAX_TRAJECTORY_SECONDS,
        description="Cut each drive to this long (s after the rest; none: the drive's own length).",
    )
    settings: dict | None = Field(
        None,
        description="Odometry settings run beside the defaults (a JSON object: GenZ-LIO's by section, DLIO's by "
        "name; none: the defaults only).",
    )


class SceneConfig(Section):
    """`lf3pm scene` and lf3pm.build_scene."""

    seed: int = Field(0, ge=0, le=MAX_SEED, description="Seed of the scene's randomness (0 to 2^63 - 1).")


class Config(Section):
    """Every section; what ``--config FILE.yaml`` holds (any subset)."""

    sensor: str = Field("vlp16", min_length=1, description="Sensor preset name or YAML file (see `lf3pm sensors`).")
    map: MapConfig = MapConfig()
    scan: ScanConfig = ScanConfig()
    metric: MetricConfig = MetricConfig()
    prediction: PredictionConfig = PredictionConfig()
    mde: MdeConfig = MdeConfig()
    solm: SolmConfig = SolmConfig()
    robot: RobotConfig = RobotConfig()
    quadrotor: QuadrotorConfig = QuadrotorConfig()
    guidance: GuidanceConfig = GuidanceConfig()
    planner: PlannerConfig = PlannerConfig()
    ground: GroundConfig = GroundConfig()
    replay: ReplayConfig = ReplayConfig()
    localization: LocalizationConfig = LocalizationConfig()
    kiss_icp: KissIcpConfig = KissIcpConfig()
    run: RunConfig = RunConfig()
    table1: Table1Config = Table1Config()
    correlation: CorrelationConfig = CorrelationConfig()
    benefit: BenefitConfig = BenefitConfig()
    gobi: GobiConfig = GobiConfig()
    odometries: OdometriesConfig = OdometriesConfig()
    scene: SceneConfig = SceneConfig()


def core_struct(struct, **fields):
    """``struct`` (a bound C++ parameter struct) with ``fields`` set; an unknown name is an error."""
    for name, value in fields.items():
        if not hasattr(struct, name):
            raise AttributeError(f"{type(struct).__name__} has no field {name!r}")
        setattr(struct, name, value)
    return struct


def scan_params(
    min_range: float,
    max_range: float,
    *,
    noise: float = 0.0,
    seed: int = 0,
    stream: int = 0,
    scan_voxel: float = 0.0,
    threads: int = 0,
    returns=None,
) -> _core.ScanParams:
    """The core's ScanParams (values as given: ScanConfig validates what users set);
    ``returns``: the sensor's lf3pm.sensors.ReturnModel (None: every hit returns)."""
    params = core_struct(
        _core.ScanParams(),
        min_range=float(min_range),
        max_range=float(max_range),
        noise_sigma=float(noise),
        seed=int(seed),
        stream=int(stream),
        scan_voxel=float(scan_voxel),
        threads=int(threads),
    )
    if returns is not None:
        params.returns = returns.core()
    return params


def validated(section: type[Section], where: str = "", flags: dict | None = None, **values) -> Section:
    """``section(**values)``, or ConfigError naming the first bad value in one line
    (as ``flags[name]`` when given, else ``where.name``)."""
    try:
        return section(**values)
    except ValidationError as err:
        raise ConfigError(describe(err, where, flags)) from None


def configured(config: Config | None, sections: tuple[str, ...], what: str, **parameters) -> Config:
    """``config`` (None: the defaults) with ``parameters`` (field names of ``sections``,
    which share none) set in their sections and validated there: ConfigError naming
    ``section.name`` for a bad value, Lf3pmError naming ``what`` for a name no section
    holds. How an entry point taking a Config whole also takes its fields by name."""
    config = DEFAULTS if config is None else config
    if not isinstance(config, Config):
        raise Lf3pmError(f"{what}: config must be an lf3pm.config.Config, got {type(config).__name__}")
    owner = {name: section for section in sections for name in type(getattr(config, section)).model_fields}
    unknown = sorted(set(parameters) - set(owner))
    if unknown:
        raise Lf3pmError(
            f"{what} has no parameter {unknown[0]!r}; it takes the fields of the "
            f"{', '.join(sections)} sections of lf3pm.config"
        )
    updates = {}
    for section in sections:
        given = {name: value for name, value in parameters.items() if owner[name] == section}
        if given:
            current = getattr(config, section)
            updates[section] = validated(type(current), section, **{**current.model_dump(), **given})
    return config.model_copy(update=updates) if updates else config


def check_threads(threads) -> int:
    """``threads`` checked as ScanConfig.threads is (0 = all cores)."""
    return validated(ScanConfig, threads=threads).threads


def describe(err: ValidationError, where: str = "", flags: dict | None = None) -> str:
    """One line for a pydantic error: the parameter (its CLI flag when given), what is wrong, the value."""
    first = err.errors(include_url=False)[0]
    path = clip(_parameter(first["loc"]))
    name = (flags or {}).get(path) or (f"{where}.{path}" if where and path else where or path)
    message = first["msg"]
    if first["type"] == "invalid_key":  # a YAML key such as 1 or 2.5
        return f"{name + ': ' if name else ''}key {excerpt(first['input'])} is not a parameter name"
    if first["type"] == "value_error":  # a check across fields (a model validator's)
        text = message.removeprefix("Value error, ")
        return f"{name}: {text}" if name else text
    if first["type"] == "finite_number":
        message = "must be finite"
    elif message.startswith("Input should be "):
        message = "must be " + message[len("Input should be ") :]
    elif first["type"] == "extra_forbidden":
        message = "is not a parameter lf3pm knows"
    value = first.get("input")
    quoted = first["type"] not in ("extra_forbidden", "missing") and not isinstance(value, dict)
    shown = f", got {excerpt(value)}" if quoted else ""
    return f"{name} {message}{shown}"


def _parameter(loc) -> str:
    """section.name of an error's location (an element of a tuple names its parameter)."""
    return ".".join(str(part) for part in loc if not isinstance(part, int))


def load_config(path: str | Path | None = None, overrides: dict | None = None, flags: dict | None = None) -> Config:
    """The configuration of ``path`` (YAML; None: the defaults), then ``overrides``.

    ``overrides``: {"section.name": value} (None values are skipped: an option not given);
    ``flags``: {"section.name": "--flag"}, to name the flag in an error. Raises ConfigError.
    """
    data: dict = {}
    if path is not None:
        text = read_text_file(path, "config", ConfigError)
        try:
            loaded = load_yaml(text, path, ConfigError)
        except yaml.YAMLError as err:
            raise ConfigError(f"{path}: not YAML ({clip(str(err).splitlines()[0])})") from None
        if loaded is not None and not isinstance(loaded, dict):
            raise ConfigError(f"{path}: a config is a mapping of sections, got {type(loaded).__name__}")
        data = loaded or {}
    for key, value in (overrides or {}).items():
        section, _, name = key.rpartition(".")
        current = data.get(section) if section else None
        if value is None or not isinstance(current, (dict, type(None))):
            continue  # not given, or the file's section is not a mapping (reported below)
        if section:
            data[section] = {**(current or {}), name: value}
        else:
            data[name] = value
    try:
        return Config.model_validate(data)
    except ValidationError as err:
        loc = _parameter(err.errors(include_url=False)[0]["loc"])
        if flags and loc in flags and (overrides or {}).get(loc) is not None:
            raise ConfigError(describe(err, flags=flags)) from None
        raise ConfigError((f"{path}: " if path is not None else "") + describe(err)) from None


def to_yaml(config: Config) -> str:
    """``config`` as YAML that :func:`load_config` reads back to the same values."""
    data = config.model_dump(mode="json")
    robot = config.robot
    if robot.vmax_norm is None or robot.vmax_norm == max(robot.vmax_lon, robot.vmax_lat):
        del data["robot"]["vmax_norm"]  # derived from the speed limits unless set
    return yaml.safe_dump(data, sort_keys=False, default_flow_style=False)


def default(path: str):
    """The default of ``section.name`` (for the CLI's help)."""
    section, _, name = path.rpartition(".")
    owner = getattr(DEFAULTS, section) if section else DEFAULTS
    return getattr(owner, name)


def help_with_default(path: str, text: str | None = None) -> str:
    """The parameter's description (or ``text``) with its default."""
    section, _, name = path.rpartition(".")
    model = type(getattr(DEFAULTS, section)) if section else Config
    description = text
    if description is None:
        field = getattr(model, "model_fields", {}).get(name)
        description = field.description if field is not None else ""
    value = default(path)
    if value is None:
        return description
    if isinstance(value, float) and math.isfinite(value):
        value = f"{value:g}"
    return f"{description} (default: {value})"


#: Every default, in one object.
DEFAULTS = Config()
