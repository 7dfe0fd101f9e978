"""``lf3pm view``: the map, its SOLM, plans, flights, replays and recorded runs in 3D in the
browser (viser).

    from lf3pm.view import load_view_inputs, serve
    app = serve(load_view_inputs("map.npy", "solm.zarr", ["plan.csv"], ["replay.json"]), port=8080)
    ...
    app.stop()
    run = load_view_inputs("map.npy", run_path="drive.bag", audit_path="out/audit.json")
    flight = serve(load_view_inputs("map.npy", "r3yaw.zarr", flights=["flight.csv"]), z=2.0)

:mod:`lf3pm.view.inputs` reads and checks what is given (one-line errors before anything
is served), :mod:`lf3pm.view.layers` turns lf3pm's objects into the arrays drawn, and
:mod:`lf3pm.view.app` is the page and its controls (a cell's evaluation, plans between
clicked poses, a recorded scan over the map beside its simulation), which call lf3pm's
public API. docs/view.md says what the page shows.
"""

from lf3pm.view.app import ViewApp, serve
from lf3pm.view.inputs import (
    RunInputs,
    ViewInputs,
    check_host,
    check_port,
    free_port,
    load_run_inputs,
    load_view_inputs,
    read_flight_csv,
    read_scan,
)

__all__ = [
    "RunInputs",
    "ViewApp",
    "ViewInputs",
    "check_host",
    "check_port",
    "free_port",
    "load_run_inputs",
    "load_view_inputs",
    "read_flight_csv",
    "read_scan",
    "serve",
]
