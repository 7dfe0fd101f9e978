"""Quadrotors (issue 43): a quadrotor's flatness map from position and yaw to thrust,
attitude and body rates (cpp/lf3pm/flight/flatness.hpp), its flight limits, and the LiDAR
it carries on a mount whose pose follows the attitude. docs/flight.md."""

from lf3pm.flight.mounts import MOUNTS, SensorMount
from lf3pm.flight.quadrotor import FlightAttitudes, Quadrotor

__all__ = ["MOUNTS", "FlightAttitudes", "Quadrotor", "SensorMount"]
