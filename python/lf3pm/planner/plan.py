"""Perception-aware planning on a SOLM: the front end's least-cost grid path,
then the back end's MINCO trajectory through it (paper, section "Planning").

Both ends trade time against the same normalised cost layer c (a SOLM channel
divided by its median, cost_map.py): the front end's edge cost is
length * (1 + weight * c) and the back end integrates (rho_T + w_q * c) dt with
w_q = weight * rho_T, which at constant speed is the same trade-off.
Cars (turning radius R > 0) get a forward-only Hybrid-A* path instead of the
grid path (planner/hybrid_search.py): it leaves and reaches rest along the
start and goal yaws, looping where they point away from each other, which the
back end's local optimiser cannot invent from a grid path.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from lf3pm.config import COST_CHANNELS, DEFAULTS, GuidanceConfig, PlannerConfig, validated
from lf3pm.errors import Lf3pmError
from lf3pm.grid import Space
from lf3pm.grid_field import GridField
from lf3pm.planner.cost_map import CostLayer, cost_from_solm
from lf3pm.planner.esdf import Esdf
from lf3pm.planner.graph_search import GraphPath, search_path
from lf3pm.planner.hybrid_search import HybridPath, search_car_path
from lf3pm.planner.poses import as_pose
from lf3pm.planner.shortcut import shortcut_path
from lf3pm.solm.reader import Solm
from lf3pm.trajectory.robots import Robot
from lf3pm.trajectory.trajectory import CSV_RATE, Trajectory
from lf3pm.trajectory.trajectory_optimizer import ESDF_MARGIN, OptimizeResult, optimize_trajectory


@dataclass
class Plan:
    """A planned motion: the front end's path (a grid path, or a car's forward
    path) and the optimised trajectory."""

    metric: str
    robot: Robot
    path: GraphPath | HybridPath
    optimization: OptimizeResult

    @property
    def trajectory(self) -> Trajectory:
        return self.optimization.trajectory

    def summary(self) -> dict:
        """Plain numbers for reports: lengths, duration, timings, worst constraint values."""
        samples = self.trajectory.sample(CSV_RATE)
        length = float(np.hypot(np.diff(samples["x"]), np.diff(samples["y"])).sum())
        return {
            "metric": self.metric,
            "robot": self.robot.kind,
            "path_length_m": self.path.length,
            "trajectory_length_m": length,
            "duration_s": float(self.trajectory.duration),
            "search_s": self.path.time,
            "optimize_s": self.optimization.wall_time,
            "iterations": int(self.optimization.iterations),
            "time_scale": float(self.optimization.time_scale),
            "limited_by": self.optimization.limited_by,
            "violations": {k: float(v) for k, v in self.optimization.violations.items()},
            "warnings": self.warnings(),
        }

    def warnings(self) -> list[str]:
        """One line per way the optimised trajectory falls short of what the user asked
        for. Speeds, rates and accelerations always hold (time is stretched until they do,
        trajectory_optimizer.within_limits); the path's geometry is kept by penalties
        (docs/planner_backend.md): a tight passage can leave a plan inside ``r_safe``, a
        car's path can turn tighter than its radius. Those are returned, not hidden."""
        out = []
        violations = self.optimization.violations
        clearance = violations.get("min_clearance")
        if clearance is not None and clearance < 0.0:
            body = self.robot.r_safe + clearance  # the ESDF is the body's distance to the map
            contact = "it touches the map" if body <= 0.0 else f"the body passes {body:.2f} m from the map"
            out.append(f"the trajectory comes {-clearance:.2f} m inside r_safe ({self.robot.r_safe:.2f} m): {contact}")
        if violations.get("max_turn_excess", 0.0) > 0.0:
            out.append(
                f"the car turns tighter than its min_turn_radius ({self.robot.min_turn_radius:.2f} m): "
                f"R |omega| exceeds |v| by up to {violations['max_turn_excess']:.3f} m/s"
            )
        return out


class Planner:
    """Plans on one SOLM with the planner section ``config`` (lf3pm.config.PlannerConfig;
    ``unknown_policy`` given overrides its ``unknown``): the ESDF and cost layers are
    computed once and reused for every (start, goal, metric) query."""

    def __init__(self, solm: Solm, config: PlannerConfig = DEFAULTS.planner, *, unknown_policy: str | None = None):
        if not solm.grid_spec.space.ground:
            space = solm.grid_spec.space
            hint = " (flights: lf3pm.planner.flight_plan.plan_flight)" if space is Space.R3YAW else ""
            raise Lf3pmError(f"planning needs an r2 or se2 SOLM (ground robots); this one is {space.value}{hint}")
        if not isinstance(config, PlannerConfig):
            raise Lf3pmError(f"a Planner's config is an lf3pm.config.PlannerConfig, got {type(config).__name__}")
        if unknown_policy is not None:
            config = validated(PlannerConfig, "planner", **{**config.model_dump(), "unknown": unknown_policy})
        self.solm, self.config = solm, config
        self.esdf = Esdf.from_solm(solm, unknown_policy=config.unknown)
        self._esdf_field = self.esdf.grid_field()
        # Clearance samples along front-end paths, at most clearance_step apart (quarter SOLM
        # cells where finer), not every quarter of the ESDF's finer cells (slow).
        self._sample_step = min(self.esdf.res / 4, config.clearance_step)
        self._layers: dict[tuple, CostLayer] = {}

    def cost_layer(self, metric: str, power: float = DEFAULTS.guidance.power) -> CostLayer:
        """The cost layer of a SOLM channel raised to ``power`` (cost_map.py), computed once."""
        if metric not in COST_CHANNELS:
            raise Lf3pmError(f"metric must be one of {', '.join(COST_CHANNELS)}, got {metric!r}")
        key = (metric, 1.0 if metric == "none" else float(power))
        if key not in self._layers:
            self._layers[key] = cost_from_solm(self.solm, metric, power=power)
        return self._layers[key]

    def plan(
        self,
        start,
        goal,
        *,
        robot: Robot = Robot(),
        guidance: GuidanceConfig = DEFAULTS.guidance,
        rho_T: float = 1.0,
        heuristic: bool = True,
        metric: str | None = None,
        weight: float | None = None,
        power: float | None = None,
        turn_radius: float | None = None,
    ) -> Plan:
        """Plans from ``start`` to ``goal`` (x, y, yaw) for ``robot`` with the guidance
        section ``guidance`` (lf3pm.config.GuidanceConfig): guided by its ``metric``
        (``none``: shortest and fastest only) raised to its ``power``, with trade-off
        ``weight`` (lambda); its ``turn_radius`` prices a turn of the sensor as the arc a
        point this far from the rotation axis travels (m per rad; graph_search.py). Those
        four given by name (not None) override the section's, validated by it."""
        if not isinstance(guidance, GuidanceConfig):
            raise Lf3pmError(f"guidance must be an lf3pm.config.GuidanceConfig, got {type(guidance).__name__}")
        given = dict(metric=metric, weight=weight, power=power, turn_radius=turn_radius)
        given = {name: value for name, value in given.items() if value is not None}
        if given:
            guidance = validated(GuidanceConfig, "guidance", **{**guidance.model_dump(), **given})
        metric, weight, power, turn_radius = guidance.metric, guidance.weight, guidance.power, guidance.turn_radius
        start, goal = as_pose(start, "start"), as_pose(goal, "goal")
        if not (math.isfinite(rho_T) and rho_T > 0):
            raise Lf3pmError(f"rho_T must be a positive number, got {rho_T}")
        layer = self.cost_layer(metric, power)
        cost = None if metric == "none" else GridField.on(self.esdf.grid, layer.filled)
        piece_length, corners, turn_price = 2.0, False, 0.0
        if robot.kind == "car" and robot.min_turn_radius > 0:
            path = search_car_path(
                cost,
                self.esdf,
                start,
                goal,
                radius=robot.min_turn_radius,
                weight=weight,
                clearance=robot.r_safe + ESDF_MARGIN,
                heuristic=heuristic,
                sample_step=self._sample_step,
                esdf_field=self._esdf_field,
            )
            waypoints = path.poses
            # Pieces of a quarter turn at most, so the spline can follow the path's loops.
            piece_length = min(piece_length, 0.5 * math.pi * robot.min_turn_radius)
        else:
            path = search_path(
                layer,
                self.esdf,
                self.solm.grid_spec,
                start,
                goal,
                weight=weight,
                heuristic=heuristic,
                r_safe=robot.r_safe,
                turn_radius=turn_radius,
            )
            waypoints = np.array(path.poses, dtype=np.float64)
            # The search snaps start and goal to cell centres; the trajectory ends on them exactly.
            waypoints[0], waypoints[-1] = start, goal
            # The exact end yaws may sit a turn away from the path's unwrapped bins.
            waypoints[:, 2] = np.unwrap(waypoints[:, 2])
            # Straighten the staircase where that keeps the clearance the optimiser's penalty
            # asks for and costs no more under the front end's own edge cost. An omni robot on
            # an SE(2) SOLM keeps the front end's yaws (the sensor's heading is the plan there);
            # otherwise the yaw is the direction of travel.
            oriented = robot.kind == "omni" and cost is not None and cost.yaw_bins > 1
            keep = shortcut_path(
                waypoints,
                self._esdf_field,
                robot.r_safe + ESDF_MARGIN,
                cost,
                weight,
                step=self._sample_step,
                yaw="interpolate" if oriented else "travel",
                turn_radius=turn_radius,
            )
            waypoints, corners = waypoints[keep], True
            # The back end prices the sensor's turns as the front end does (a turn_radius of
            # travel per rad), or it turns where the front end judged turning not to pay.
            turn_price = turn_radius / robot.vmax_lon if oriented else 0.0
        result = optimize_trajectory(
            waypoints,
            cost,
            self._esdf_field,
            robot,
            w_q=weight * rho_T,
            rho_T=rho_T,
            esdf_margin=ESDF_MARGIN,
            piece_length=piece_length,
            corners=corners,
            turn_price=turn_price,
        )
        return Plan(metric, robot, path, result)
