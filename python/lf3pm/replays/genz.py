"""GenZ-LIO (PyPI ``genz-lio``, GPL-2.0-only), the lio replay's odometry for a
non-repetitive (Livox) sensor: a FAST-LIO2-style iterated error-state Kalman filter on a
voxel map, run with point-to-plane updates only. lf3pm runs it in the worker process only
(_lio_worker.GenZ); ``make build`` replaces PyPI's wheel by lf3pm's build of its sdist
(third_party/genz_lio, :attr:`GenZ.build`), whose one change lets the initial covariance
be set. docs/lio.md has the measurements behind each setting.

Conventions (GenZ-LIO 0.1.1, read from its source): IMU rows t, ax, ay, az, gx, gy, gz in
s, m/s^2 and rad/s, each scan given the samples with t in (previous scan end, scan end];
per-point times are float32 offsets in seconds from the earliest return (absolute times
in float32 would lose milliseconds); the pose (``lidar_pose``) is the LiDAR's at the scan
end in the odometry's frame, which is the IMU's while GenZ-LIO initialises on its first
20+ IMU samples (it takes the sensor to be still then). LiDAR-IMU extrinsic: the IMU
samples' (identity for a ground robot's, a flight's mount), as its extrinsic_r and
extrinsic_t (the LiDAR in the IMU's frame), not estimated online.
"""

from __future__ import annotations

import warnings

from pydantic import ConfigDict, Field, model_validator

from lf3pm.config import Section, validated
from lf3pm.errors import Lf3pmError
from lf3pm.replays.adapters import WORKER_MODULE, Odometry
from lf3pm.replays.imu import ImuPreset


class GenzSettings(Section):
    """GenZ-LIO's settings by section of its Config (``mapping``, ``preprocess``,
    ``adaptive_voxelization``, ``hybrid_metric``, ``noise_model``) and lf3pm's
    ``initial_covariance``; GenZ-LIO's own defaults for what is not given."""

    model_config = ConfigDict(extra="allow", allow_inf_nan=False, frozen=True)

    hybrid_metric: dict = Field(
        {"enable": False},
        description="Point-to-plane residuals only, FAST-LIO2's: GenZ-LIO's point-to-point ones made the "
        'estimate lag the truth (docs/lio.md, "The start-of-motion lag").',
    )
    initial_covariance: dict = Field(
        {"pose_variance": 1e-4},
        description="Variance of position, rotation and velocity at the start (m^2, rad^2, (m/s)^2; lf3pm's "
        "build only): 1 cm, 0.01 rad, 0.01 m/s, where GenZ-LIO's own 1 let a still sensor's estimate slide "
        '(docs/lio.md, "A still sensor").',
    )
    noise_inflation: float = Field(
        100.0,
        gt=0,
        le=1e12,
        description="Factor on the simulated IMU's noise variances the filter is told (docs/lio.md).",
    )

    @model_validator(mode="after")
    def _sections(self):
        for section, values in (self.model_extra or {}).items():
            if not isinstance(values, dict):
                raise ValueError(
                    f"GenZ-LIO settings go by section, e.g. mapping={{'voxel_size': 0.5}}; got {section}={values!r}"
                )
        return self


class GenZ(Odometry):
    """GenZ-LIO (module docstring)."""

    key = "genz"
    name = "GenZ-LIO"
    package = "genz-lio"
    version = "0.1.1"
    licence = "GPL-2.0-only"
    worker = f"{WORKER_MODULE}:GenZ"
    install = "pip install 'lf3pm[lio]' (wheels for Python 3.8-3.12)"
    Settings = GenzSettings
    auto_for = (False,)
    takes_extrinsic = True
    #: The version lf3pm's build of GenZ-LIO reports (third_party/genz_lio); PyPI's wheel
    #: reports :attr:`version` and runs at GenZ-LIO's own initial covariance, with a warning.
    build = "0.1.1+lf3pm.1"

    @classmethod
    def settings(cls, params: dict) -> GenzSettings:
        """lf3pm's settings with ``params`` merged field by field within each section."""
        defaults = GenzSettings()
        merged = {}
        for section, values in params.items():
            current = getattr(defaults, section, None)
            if isinstance(current, dict) and isinstance(values, dict):
                values = {**current, **values}
            elif section != "noise_inflation" and not isinstance(values, dict):
                raise Lf3pmError(
                    f"GenZ-LIO settings go by section, e.g. mapping={{'voxel_size': 0.5}}; got {section}={values!r}"
                )
            merged[section] = values
        return validated(GenzSettings, cls.key, **merged)

    @classmethod
    def worker_settings(cls, settings: GenzSettings, sensor, imu) -> dict:
        """GenZ-LIO's sections: lf3pm's, the IMU's noise (:func:`imu_noise_model`), then
        the sections a caller gave."""
        given = dict(settings.model_extra or {})
        noise = {**imu_noise_model(imu, settings.noise_inflation), **given.pop("noise_model", {})}
        return {
            "hybrid_metric": dict(settings.hybrid_metric),
            "initial_covariance": dict(settings.initial_covariance),
            "noise_model": noise,
            **given,
        }

    @classmethod
    def recorded(cls, settings: dict, version: str, messages: list) -> dict:
        if version != cls.build:  # PyPI's build ignores the initial covariance it is given
            settings = {**settings, "initial_covariance": {"pose_variance": 1.0}}
            messages.insert(
                0,
                f"lf3pm: genz-lio {version} is not lf3pm's build ({cls.build}), so it "
                "starts at GenZ-LIO's own initial covariance (1 m, 1 rad): a still narrow-view "
                "sensor's estimate slides before it moves (docs/lio.md, 'A still sensor'); "
                "`make build` installs lf3pm's (third_party/genz_lio)",
            )
            warnings.warn(messages[0], stacklevel=3)
        return {"lidar_type": "livox", "overrides": settings}


def imu_noise_model(imu, inflation: float = GenzSettings().noise_inflation) -> dict:
    """GenZ-LIO's IMU process noise for samples made by simulate_imu: their preset at
    their rate, variances times ``inflation``; empty (GenZ-LIO's defaults) for other IMU
    data.

    GenZ-LIO (IKFoM) adds (dt F_w) Q (dt F_w)^T per IMU step, so a white noise of
    per-sample sigma enters as a variance sigma^2 (acc_cov, gyr_cov) and a random walk of
    density K as K^2 * rate (b_acc_cov, b_gyr_cov).
    """
    preset, rate = getattr(imu, "preset", None), getattr(imu, "rate", None)
    if not isinstance(preset, ImuPreset) or rate is None:
        return {}
    sigma = preset.sigmas(float(rate))
    exact = {
        "acc_cov": sigma["accel_white"] ** 2,
        "gyr_cov": sigma["gyro_white"] ** 2,
        "b_acc_cov": (sigma["accel_bias_step"] * rate) ** 2,
        "b_gyr_cov": (sigma["gyro_bias_step"] * rate) ** 2,
    }
    # A noiseless preset says nothing about a real IMU: GenZ-LIO's defaults stay for those terms.
    return {key: inflation * value for key, value in exact.items() if value > 0}
