"""The flight study's protocol (issue 43, item 7): every rule, scene and setting of a run,
fixed in one YAML before the run that is reported (`lf3pm experiment flight --protocol`),
as the benefit study's is. A change after seeing results is a new protocol (new pairs).

Three planners on the same r3yaw SOLM and pairs (lf3pm.planner.flight_plan.PLANNERS):
(a) velocity_yaw, (b) yaw_only, (c) joint. A pair is at risk when plan (a) crosses poor
views on its SOLM (lf3pm.experiments.risk's rule on the SOLM's q_n at the plan's poses,
level, against the map's median over each cell's best yaw), decided before any replay.
The joint planner corrects its guidance for the attitude it flies at in
``attitude_rounds`` rounds (lf3pm.planner.flight_attitude; by default none: level
guidance, as the protocols frozen before that correction existed flew).
Every plan is replayed by each odometry with each seed; a plan's error is the median over
seeds of the replay's APE (RMSE, m)."""

from __future__ import annotations

from pathlib import Path

from pydantic import Field

from lf3pm.config import Section, validated
from lf3pm.errors import Lf3pmError
from lf3pm.experiments.risk import RiskRule
from lf3pm.limits import load_yaml, read_text_file
from lf3pm.planner.flight_attitude import ATTITUDE_ROUNDS
from lf3pm.planner.flight_plan import MAX_ATTITUDE_ROUNDS


class FlightMap(Section):
    """One scene of the study: its start/goal volumes give ``pairs`` pairs (start drawn in
    the start volume, goal in the goal volume; every second pair flown goal to start), its
    r3yaw SOLM at ``res`` m with levels every ``level_step`` m from ``z_min`` to ``z_max``."""

    scene: str
    pairs: int = Field(6, ge=1, le=1000)
    res: float = Field(1.0, gt=0, le=10)
    z_min: float = Field(1.0)
    z_max: float = Field(4.0)
    level_step: float = Field(1.0, gt=0)
    margin: float = Field(2.0, ge=0, description="SOLM bounds: the volumes' extent widened by this (m) ...")
    bounds: tuple[float, float, float, float] | None = Field(None, description="... or these (xmin ymin xmax ymax).")


class FlightProtocol(Section):
    """Everything a flight study run depends on (module docstring)."""

    name: str = "flight"
    maps: list[FlightMap] = Field(
        default_factory=lambda: [
            FlightMap(scene="drift", bounds=(-40.0, -6.0, 40.0, 20.0), z_max=3.0),
            FlightMap(scene="forest", bounds=(-25.0, -16.0, 25.0, 16.0), z_max=4.0),
            FlightMap(scene="bridge", bounds=(-30.0, -8.0, 30.0, 8.0), z_min=2.0, z_max=5.0),
            FlightMap(scene="open_field", bounds=(-42.0, -8.0, 42.0, 16.0), z_max=9.0),
        ]
    )
    sensor: str = Field("vlp16", description="The LiDAR (a preset or YAML).")
    mount: str = Field("down20", description="Where it sits on the body (quadrotor.mount).")
    yaw_bins: int = Field(6, ge=1, le=360)
    ray_stride: int = Field(4, ge=1, le=100, description="SOLM builds cast every K-th column (docs/solm.md).")
    odometries: list[str] = Field(default_factory=lambda: ["genz", "dlio"], min_length=1)
    seeds: int = Field(3, ge=1, le=100)
    pair_seed: int = Field(0, ge=0)
    risk: RiskRule = RiskRule()
    attitude_rounds: int = Field(
        ATTITUDE_ROUNDS,
        ge=0,
        le=MAX_ATTITUDE_ROUNDS,
        description="Rounds of the joint planner's guidance at the planned attitude (0: the level SOLM only).",
    )
    threads: int = Field(2, ge=1, le=256)

    @classmethod
    def quick(cls) -> FlightProtocol:
        """A minutes-long run for tests and a first look: one small map, two pairs, one
        odometry, one seed."""
        return cls(
            name="flight-quick",
            maps=[FlightMap(scene="atrium", pairs=2, res=1.5, z_min=1.5, z_max=15.0, level_step=1.5, margin=1.5)],
            odometries=["genz"],
            seeds=1,
            ray_stride=4,
        )


def load_protocol(path) -> FlightProtocol:
    """The protocol in the YAML file ``path`` (any subset of the fields; Lf3pmError in one
    line naming the file and the bad value)."""
    import yaml

    path = Path(path)
    try:
        data = load_yaml(read_text_file(path, "flight protocol", Lf3pmError), f"flight protocol {path}", Lf3pmError)
    except yaml.YAMLError as err:
        raise Lf3pmError(f"flight protocol {path}: invalid YAML ({type(err).__name__})") from None
    if not isinstance(data, dict):
        raise Lf3pmError(f"flight protocol {path}: expected a mapping of fields")
    return validated(FlightProtocol, str(path), **data)
