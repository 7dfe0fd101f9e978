"""`lf3pm evaluate` and `lf3pm mde`: the metric and its ground truth at one pose."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import typer
from rich.table import Table

from lf3pm.atomic import atomic_write
from lf3pm.cli._common import (
    CONFIG_OPTION,
    MAP_PATHS,
    SCAN_PATHS,
    app,
    check_output,
    configure,
    console,
    map_loading,
    option,
    user_errors,
)


@app.command()
def evaluate(
    map_path: Path = typer.Argument(..., metavar="MAP", help="Point-cloud map (.pcd .ply .las .laz .npy .npz)."),
    pose: tuple[float, float, float, float] = typer.Option(..., help="Sensor pose X Y Z YAW (m, rad)."),
    config: Path | None = CONFIG_OPTION,
    sensor: str | None = option("sensor"),
    seed: int | None = option("scan.seed"),
    noise: float | None = option("scan.noise"),
    dof: int | None = option("metric.dof"),
    w1: float | None = option("metric.w1"),
    scan_voxel: float | None = option("scan.scan_voxel"),
    association: str | None = option("metric.association"),
    map_voxel: float | None = option("map.voxel"),
    knn: int | None = option("map.knn"),
    plane_threshold: float | None = option("map.plane_threshold"),
    max_neighbor_distance: float | None = option("map.max_neighbor_distance"),
    threads: int | None = option("scan.threads"),
    calibration: str | None = option("prediction.calibration", metavar="FIT.json"),
    as_json: bool = typer.Option(False, "--json", help="Print one JSON object."),
    save_observations: Path | None = typer.Option(None, metavar="OBS.npz", help="Write A, b and the simulated points."),
):
    """Simulate the scan at one pose and print the LF-3PM metric and baselines."""
    with user_errors():
        cfg = configure(
            config,
            locals(),
            {
                **SCAN_PATHS,
                **MAP_PATHS,
                "dof": "metric.dof",
                "w1": "metric.w1",
                "association": "metric.association",
                "calibration": "prediction.calibration",
            },
        )
        from lf3pm.map import load_map
        from lf3pm.metric import evaluate as run_evaluate

        check_output(save_observations)
        with map_loading() as progress:
            world = load_map(map_path, cfg.map, threads=cfg.scan.threads, progress=progress)
        result = run_evaluate(world, pose, cfg.sensor, cfg, observations=save_observations is not None)
        if save_observations is not None:
            obs = result.observations
            with atomic_write(save_observations) as fp:
                np.savez(
                    fp,
                    A=obs["A"],
                    b=obs["b"],
                    points=obs["points"],
                    sensor_points=obs["sensor_points"],
                    row_hit=obs["row_hit"],
                    pose=np.asarray(result.pose),
                )
        out = result.to_dict()
        out["map"] = world.describe()
        if as_json:
            print(json.dumps(out))
            return
        print_evaluation(out)


def print_evaluation(out: dict) -> None:
    table = Table(title=f"LF-3PM metric, sensor {out['sensor']}", show_header=True)
    table.add_column("quantity")
    table.add_column("value", justify="right")
    for key in (
        "q_min",
        "q_n",
        "q_max",
        "sigma1",
        "xi",
        "zhang",
        "condition_number",
        "cov_trace",
        "step_norm",
        "residual_norm",
        "scaled_cov_trace",
    ):
        value = out[key]
        table.add_row(key, "inf" if value is None else f"{value:.6g}")
    reasons = []
    for label, key, interval, withheld in (
        ("predicted MDE", "predicted_mde", "predicted_mde_interval", "predicted_mde_withheld"),
        (
            "predicted localization error (m)",
            "predicted_localization_error_m",
            "predicted_localization_error_interval_m",
            "predicted_localization_error_withheld",
        ),
    ):
        if out[key] is not None:
            lo, hi = out[interval]
            table.add_row(label, f"{out[key]:.3g} [{lo:.2g}, {hi:.2g}]")
        else:
            table.add_row(label, "withheld")
            reasons.append(f"{label.removesuffix(' (m)')} withheld: {out[withheld]}")
    table.add_row("least observable direction", " ".join(f"{v:+.3f}" for v in out["least_observable"]))
    table.add_row("rows m", str(out["m"]))
    table.add_row("hits / rays", f"{out['hits']} / {out['rays']}")
    table.add_row("degenerate", str(out["degenerate"]))
    console.print(table)
    for line in reasons:
        console.print(line, markup=False, highlight=False, soft_wrap=True)


@app.command()
def mde(
    map_path: Path = typer.Argument(..., metavar="MAP", help="Point-cloud map."),
    pose: tuple[float, float, float, float] = typer.Option(..., help="True sensor pose X Y Z YAW (m, rad)."),
    config: Path | None = CONFIG_OPTION,
    sensor: str | None = option("sensor"),
    trials: int | None = option("mde.trials"),
    sigma_t: float | None = option("mde.sigma_t"),
    sigma_r: float | None = option("mde.sigma_r"),
    noise: float | None = option("scan.noise"),
    seed: int | None = option("scan.seed", help="Seed of the scan noise and the disturbances."),
    scan_voxel: float | None = option("scan.scan_voxel"),
    threads: int | None = option("scan.threads"),
    as_json: bool = typer.Option(False, "--json", help="Print one JSON object."),
):
    """MDE: mean squared error of point-to-plane ICP (small_gicp) from disturbed starts."""
    with user_errors():
        cfg = configure(
            config, locals(), {**SCAN_PATHS, "trials": "mde.trials", "sigma_t": "mde.sigma_t", "sigma_r": "mde.sigma_r"}
        )
        from lf3pm.map import load_map
        from lf3pm.validation import mde as run_mde

        with map_loading() as progress:
            world = load_map(map_path, cfg.map, threads=cfg.scan.threads, progress=progress)
        result = run_mde(world, pose, cfg.sensor, cfg)
        out = result.to_dict()
        if as_json:
            print(json.dumps(out))
            return
        table = Table(title=f"MDE, sensor {result.sensor}, {result.trials} trials")
        table.add_column("quantity")
        table.add_column("value", justify="right")
        table.add_row("MDE", f"{result.mde:.6g}")
        table.add_row("median translation error (m)", f"{np.median(result.translation_errors):.4g}")
        table.add_row("median rotation error (deg)", f"{np.median(result.rotation_errors_deg):.4g}")
        table.add_row("converged", f"{result.converged} / {result.trials}")
        table.add_row("scan points", str(result.hits))
        console.print(table)
