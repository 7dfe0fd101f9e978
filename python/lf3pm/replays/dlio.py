"""DLIO (Direct LiDAR-Inertial Odometry, UCLA VECTR, MIT) as evalio compiles it: GICP
scan-to-map registration with a nonlinear geometric observer, deskewing by IMU
integration; the lio replay's odometry for a spinning sensor (docs/lio.md).

Conventions (evalio 0.6.1's DLIO, read from evalio's binding and DLIO's deskewing,
checked by the time fit of tests/test_lio.py): a scan is stamped at its first return,
each return carrying its offset from it (ns); DLIO deskews each scan to its median
distinct return time and reports the sensor's pose there. It calibrates the IMU biases
and gravity over its first ``imu_calib_time`` s, during which the sensor must be still.
evalio leaves every parameter it is not given uninitialised, so the worker sets all.
"""

from __future__ import annotations

from pydantic import ConfigDict, Field

from lf3pm.config import Section
from lf3pm.replays.adapters import WORKER_MODULE, EvalioOdometry


class DlioSettings(Section):
    """DLIO's parameters by name (evalio's ``DLIO.default_params()``; the worker refuses
    an unknown one); lf3pm's over DLIO's own."""

    model_config = ConfigDict(extra="allow", allow_inf_nan=False, frozen=True)

    imu_calib_time: float = Field(
        1.0,
        gt=0,
        le=3600,
        description="Seconds of still IMU DLIO calibrates on: inside the replay's rest (DLIO's own 3 s would "
        "take the start of the motion for a still sensor's IMU).",
    )


class Dlio(EvalioOdometry):
    """DLIO (module docstring)."""

    key = "dlio"
    name = "DLIO"
    licence = "MIT (evalio and DLIO)"
    worker = f"{WORKER_MODULE}:Dlio"
    Settings = DlioSettings
    auto_for = (True,)
    takes_extrinsic = True
    loses = {
        False: "DLIO loses track of a non-repetitive (Livox) sensor, whose 0.1 s scans cover a "
        "part of its pattern (Mid-70: 0.1-3 m APE where GenZ-LIO holds 0.4-4 cm; docs/lio.md, "
        '"Two odometries"): use odometry genz or auto'
    }

    @classmethod
    def still_for(cls, settings: dict) -> float:
        return float(settings["imu_calib_time"])
