"""The flight study (issue 43, item 7; `lf3pm experiment flight`): quadrotor flights by
three planners on the same r3yaw SOLMs and pairs, judged by LIO replays at the flatness
attitude (docs/flight.md)."""

from lf3pm.experiments.flight.analysis import analyse, write_report
from lf3pm.experiments.flight.protocol import FlightMap, FlightProtocol, load_protocol
from lf3pm.experiments.flight.study import report_folder, run_study

__all__ = ["FlightMap", "FlightProtocol", "analyse", "load_protocol", "report_folder", "run_study", "write_report"]
