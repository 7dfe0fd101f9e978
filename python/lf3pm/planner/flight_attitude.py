"""The guidance at the planned attitude (issue 43, item 2): an r3yaw SOLM is cast with the
body level, but a quadrotor flies tilted by its acceleration, and near the tilt limit that
changes q_n by 4-15 % (median, docs/flight.md "What the level attitude costs"). The back end
therefore corrects the level SOLM along the flight it plans: it samples the flight every
half cell, casts the SOLM's sensor there at the flatness attitude and at level (the same
position, yaw, rays, noise stream and metric), and multiplies the cost of the nodes the
flight passes by the ratio of the two, raised to the guidance power; then it optimises
again from that flight. The correction is held fixed during an optimisation (a round), so
each round's objective stays smooth; nodes the flight no longer passes keep their last
correction, which is the attitude a flight through them would have had."""

from __future__ import annotations

import numpy as np

from lf3pm import _core
from lf3pm.config import DEFAULTS, Config
from lf3pm.flight import Quadrotor
from lf3pm.planner.cost_map import CostLayer
from lf3pm.sensors import as_sensor
from lf3pm.solm.grid import Space

#: Rounds of correction after the level optimisation by default: none. Measured on the first
#: flight study's 24 joint flights (docs/investigations/flight_attitude_rounds.py): one round
#: changes the guidance cost met at the flown attitude by -0.1 % median (-22 % to +7 %) and
#: takes 1.7 s (median) against 0.2 s, since those flights' attitudes change q_n by 2-4 %
#: median. Ask for rounds where flights tilt more (near the tilt limit: 4-15 %).
ATTITUDE_ROUNDS = 0
#: Samples per SOLM cell edge along the flight.
SAMPLES_PER_CELL = 2


class AttitudeGuidance:
    """Casts ``solm``'s sensor (its rays, stride, noise, seed, metric weights and mount, from
    its attributes) at poses along a flight on ``world`` (a Map, the SOLM's) and corrects
    the cost ``layer`` (the guidance layer the back end reads) by what the attitude
    changes. ``config``: the scan section's threads and the metric section's other fields."""

    def __init__(self, solm, world, layer: CostLayer, power: float, config: Config = DEFAULTS):
        from lf3pm.solm.tiles import make_job

        attrs, g = solm.attrs, solm.grid_spec
        if g.space is not Space.R3YAW:
            raise ValueError("the guidance at the planned attitude needs an r3yaw SOLM")
        scan = config.scan.model_copy(update={"noise": attrs["noise"], "seed": attrs["seed"]})
        metric = config.metric.model_copy(update={"w1": attrs["w1"], "association": attrs["association"]})
        layout = config.solm.model_copy(update={"ray_stride": attrs["ray_stride"], "yaw_reuse": False})
        self.mount = np.asarray(attrs["mount"]["matrix"], dtype=np.float64)
        job = make_job(as_sensor(attrs["sensor"]), g, scan, metric, layout, self.mount)
        self.rays, self.params = job.rays, job.params(config.scan.threads)
        self.world, self.grid, self.layer, self.power = world, g, layer, power
        self.metric = layer.channel
        self.correction = np.ones(layer.filled.shape)

    def ratios(self, positions: np.ndarray, rotations: np.ndarray, yaws: np.ndarray) -> np.ndarray:
        """The guidance metric at the sensor on the body at ``positions`` (n x 3) with
        ``rotations`` (n x 3 x 3, body to world) over its value with the body level at the
        same yaw (n); +inf where only the tilted view is degenerate, NaN where the level one
        is (no ratio)."""
        n = len(positions)
        level = np.zeros((n, 3, 3))
        c, s = np.cos(yaws), np.sin(yaws)
        level[:, 0, 0], level[:, 0, 1], level[:, 1, 0], level[:, 1, 1], level[:, 2, 2] = c, -s, s, c, 1.0
        body = np.tile(np.eye(4), (2 * n, 1, 1))
        body[:, :3, :3] = np.concatenate([rotations, level])
        body[:, :3, 3] = np.concatenate([positions, positions])
        poses = np.ascontiguousarray(body @ self.mount)
        streams = np.tile(np.arange(n, dtype=np.uint64), 2)  # the same noise at both attitudes
        res = _core.evaluate_many(self.world.index, poses, streams, self.rays, self.params)
        value = np.where(res["degenerate"].astype(bool), np.inf, res[self.metric])
        tilted, flat = value[:n], value[n:]
        with np.errstate(invalid="ignore", divide="ignore"):
            return np.where(np.isfinite(flat) & (flat > 0), tilted / flat, np.nan)

    def correct(self, samples: dict, quad: Quadrotor) -> tuple[np.ndarray, dict]:
        """Corrects the layer along the sampled flight (FlightTrajectory.sample at
        :func:`sample_rate`): each node a sample falls in takes the median of its samples'
        ratios. Returns the corrected layer (float64, the layer's shape) and a summary:
        samples, the median ratio and its 5-95 % range, and the share of samples whose
        metric the attitude changes by more than 10 %."""
        derivatives = (samples[name] for name in ("velocity", "acceleration", "jerk", "yaw", "yaw_rate"))
        att = quad.attitudes(*derivatives)
        p = samples["position"]
        r = self.ratios(p, att.rotation, samples["yaw"])
        k, iy, ix = self.grid.cell(p[:, 0], p[:, 1], p[:, 2], yaw=samples["yaw"])
        node = np.ravel_multi_index((k, iy, ix), self.correction.shape)
        known = ~np.isnan(r)
        for index in np.unique(node[known]):
            self.correction.flat[index] = np.median(r[known & (node == index)])
        layer = self.layer
        with np.errstate(invalid="ignore"):  # a node degenerate only when tilted: the cap
            cost = np.where(np.isinf(self.correction), layer.cap, layer.filled * np.power(self.correction, self.power))
        cost = np.minimum(cost, layer.cap)
        finite = r[known & np.isfinite(r)]
        summary = {
            "samples": int(len(r)),
            "ratio_median": float(np.median(finite)) if len(finite) else float("nan"),
            "ratio_p5_p95": [float(x) for x in np.percentile(finite, [5, 95])] if len(finite) else [],
            "changed_over_10_percent": float(np.mean(np.abs(finite - 1.0) > 0.1)) if len(finite) else 0.0,
            "degenerate_only_tilted": int(np.sum(np.isinf(r))),
        }
        return np.where(np.isnan(layer.cost), layer.cap, cost), summary


def sample_rate(grid, vmax: float) -> float:
    """Samples a second along a flight so that at the speed limit they fall
    :data:`SAMPLES_PER_CELL` to a cell edge."""
    return SAMPLES_PER_CELL * vmax / grid.res
