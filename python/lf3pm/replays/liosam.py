"""LIO-SAM (BSD-3-Clause) as evalio compiles it: LOAM features of a ring-organised scan
matched to a keyframe map, IMU preintegration in a factor graph; spinning sensors only.
What the worker does to feed it (a level IMU made its start-up NaN, its poses come two
scans late and refer to two times) is in _lio_worker.LioSam and docs/lio.md, "The third:
LIO-SAM"."""

from __future__ import annotations

from pydantic import ConfigDict, Field

from lf3pm.config import Section
from lf3pm.replays.adapters import WORKER_MODULE, EvalioOdometry
from lf3pm.replays.imu import ImuPreset


class LiosamSettings(Section):
    """LIO-SAM's parameters by name (evalio's ``LioSAM.default_params()``; the worker
    refuses an unknown one) and ``imu_densities`` (evalio's ImuParams); lf3pm's over
    evalio's defaults."""

    model_config = ConfigDict(extra="allow", allow_inf_nan=False, frozen=True)

    mappingProcessInterval: float = Field(  # noqa: N815 (LIO-SAM's name)
        0.0,
        ge=0,
        le=3600,
        description="Seconds between scans matched to the map: 0, every scan (LIO-SAM's 0.15 s skips every "
        "other 10 Hz scan, which then repeats the pose before it).",
    )


class LioSam(EvalioOdometry):
    """LIO-SAM (module docstring)."""

    key = "liosam"
    name = "LIO-SAM"
    licence = "BSD-3-Clause (LIO-SAM), MIT (evalio)"
    worker = f"{WORKER_MODULE}:LioSam"
    Settings = LiosamSettings
    needs_rings = True
    takes_extrinsic = True

    @classmethod
    def worker_settings(cls, settings: LiosamSettings, sensor, imu) -> dict:
        """Its parameters, with the simulated IMU's noise densities (:func:`imu_densities`)
        unless a caller gave its own."""
        given = settings.model_dump()
        interval = given.pop("mappingProcessInterval")
        return {"mappingProcessInterval": interval, "imu_densities": imu_densities(imu), **given}


def imu_densities(imu) -> dict:
    """LIO-SAM's IMU noise (evalio's ImuParams: GTSAM's continuous-time densities) for
    samples made by simulate_imu: their preset's; empty (evalio's defaults) for other IMU
    data and for a noiseless preset's zero terms."""
    preset = getattr(imu, "preset", None)
    if not isinstance(preset, ImuPreset):
        return {}
    densities = {
        "accel": preset.accel_noise_density,
        "gyro": preset.gyro_noise_density,
        "accel_bias": preset.accel_bias_random_walk,
        "gyro_bias": preset.gyro_bias_random_walk,
    }
    return {key: value for key, value in densities.items() if value > 0}
