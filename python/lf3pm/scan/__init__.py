"""Scan simulation (the C++ scan/): a scan cast from one pose
(:func:`simulate_scan`), a scan whose rays fire along a motion
(:func:`simulate_moving_scan`, motion distortion) and the stream of scans a replay
consumes (:class:`ScanStream`)."""

from lf3pm.scan.moving_scan import MovingScan, simulate_moving_scan
from lf3pm.scan.scan_simulator import SimulatedScan, simulate_scan
from lf3pm.scan.scans import ScanStream

__all__ = ["MovingScan", "ScanStream", "SimulatedScan", "simulate_moving_scan", "simulate_scan"]
