"""Why a guidance's plan takes the route it takes: every front-end path of one
benefit-study pair priced under every guidance's cost (docs/benefit.md, "Why
step_norm stays in the tunnel").

For each guidance of the study (and ``none``), the planner's front end
(graph_search.search_path, as Planner.plan calls it for omni and diff robots)
finds its least-cost path; each path is then priced under each guidance's edge
cost, (l + rho |dk|) (1 + weight (c_a + c_b) / 2). Each path priced under its own
guidance must reproduce the search's own cost (checked: the pricing is right
before the cross table is read). A row whose smallest entry is not on its own
path's column would be a search that missed a cheaper path; a column cheap
under a row's cost shows what that channel fails to tell apart. Below it, each
channel over its map median (the cost layer's normalisation) along each path,
10th / 50th / 90th percentile over the path's cells.

``--coarse-mask``: the traversable cells of the SOLM's own obstacle mask (the
planner before its occupancy layer, docs/solm.md) instead of the occupancy
layer's field.

    .venv/bin/python bench/route_cost.py --study out/b4 --map tunnel --pair 00_omni
    .venv/bin/python bench/route_cost.py --study out/b4 --map tunnel --pair 00_omni --coarse-mask
"""

from __future__ import annotations

import json
import math

import numpy as np
from study_inputs import study_arguments, study_case

from lf3pm.config import DEFAULTS
from lf3pm.planner.esdf import Esdf, solm_masks
from lf3pm.planner.graph_search import search_path
from lf3pm.planner.plan import Planner
from lf3pm.solm import Solm
from lf3pm.trajectory.robots import Robot


def along(values: np.ndarray, cells: np.ndarray) -> np.ndarray:
    """``values`` ((yaw_bins, ny, nx), or (ny, nx) for r2) at each cell (ix, iy, yaw bin)."""
    layered = values if values.ndim == 3 else values[None]
    return layered[cells[:, 2], cells[:, 1], cells[:, 0]]


def path_cost(values: np.ndarray, cells: np.ndarray, res: float, weight: float, rho: float) -> float:
    """The front end's cost of the grid path ``cells`` (ix, iy, yaw bin) on the
    cost array ``values``."""
    bins = values.shape[0] if values.ndim == 3 else 1
    c = along(values, cells)
    ix, iy, k = cells[:, 0], cells[:, 1], cells[:, 2]
    length = res * np.hypot(np.diff(ix), np.diff(iy))
    dk = np.abs(np.diff(k)) % bins
    turns = np.minimum(dk, bins - dk)
    return float(np.sum((length + rho * turns) * (1.0 + weight * 0.5 * (c[1:] + c[:-1]))))


def main() -> None:
    parser = study_arguments(__doc__.split("\n\n")[0])
    parser.add_argument(
        "--coarse-mask",
        action="store_true",
        help="traversable cells from the SOLM's obstacle mask, not its occupancy layer",
    )
    args = parser.parse_args()
    case = study_case(args.map)
    summary = json.loads((args.study / "summary.json").read_text())
    number, kind = args.pair.split("_")
    pair = next(
        (p for p in summary["pairs"] if p["case"] == args.map and p["pair"] == int(number) and p["robot"] == kind), None
    )
    if pair is None:
        raise SystemExit(f"no pair {args.pair} on {args.map} in {args.study}/summary.json")
    planner = Planner(Solm.open(args.study / "solm" / f"{args.map}.zarr"))
    grid = planner.solm.grid_spec
    robot = Robot(kind, r_safe=case.r_safe)
    traversable = planner.esdf
    if args.coarse_mask:
        obstacle, unknown = solm_masks(planner.solm)
        traversable = Esdf.from_mask(
            obstacle, grid.x0, grid.y0, grid.res, unknown=unknown, body_radius=float(planner.solm.attrs["robot_radius"])
        ).traversable(robot.r_safe)
    turn_radius = DEFAULTS.guidance.turn_radius
    rho = turn_radius * 2 * math.pi / max(grid.yaw_bins, 1)
    guidance = summary["guidance"]
    layers, paths = {}, {}
    for g in guidance:
        layers[g["name"]] = planner.cost_layer(g["channel"], g["power"])
        paths[g["name"]] = search_path(
            layers[g["name"]],
            traversable,
            grid,
            pair["start"],
            pair["goal"],
            weight=g["weight"],
            r_safe=robot.r_safe,
            turn_radius=turn_radius,
        )
    for g in guidance:
        own = path_cost(layers[g["name"]].filled, paths[g["name"]].cells, grid.res, g["weight"], rho)
        if not math.isclose(own, paths[g["name"]].cost, rel_tol=1e-6):
            raise SystemExit(
                f"pricing check failed for {g['name']}: {own} against the search's {paths[g['name']].cost}"
            )

    names = [g["name"] for g in guidance]
    mask = "the SOLM's coarse obstacle mask" if args.coarse_mask else "the occupancy layer"
    print(f"{args.map} pair {args.pair} ({mask}): each column's path priced under each row's cost\n")
    print("| cost of \\ path of | " + " | ".join(names) + " |")
    print("|---" * (len(names) + 1) + "|")
    for g in guidance:
        row = [path_cost(layers[g["name"]].filled, paths[n].cells, grid.res, g["weight"], rho) for n in names]
        best = min(row)
        print(f"| {g['name']} | " + " | ".join(f"**{v:.1f}**" if v == best else f"{v:.1f}" for v in row) + " |")
    print("| length (m) | " + " | ".join(f"{paths[n].length:.1f}" for n in names) + " |")

    channels = sorted({g["channel"] for g in guidance} - {"none"})
    print("\nchannel over its map median along each path, 10th / 50th / 90th percentile of its cells\n")
    print("| channel \\ path of | " + " | ".join(names) + " |")
    print("|---" * (len(names) + 1) + "|")
    for channel in channels:
        values = planner.cost_layer(channel, 1.0).filled
        row = [np.percentile(along(values, paths[n].cells), [10, 50, 90]) for n in names]
        print(f"| {channel} | " + " | ".join(" / ".join(f"{v:.2f}" for v in r) for r in row) + " |")


if __name__ == "__main__":
    main()
