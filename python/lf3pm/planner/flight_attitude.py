"""The guidance at the planned attitude (issue 43, item 2): an r3yaw SOLM is cast with the
body level, but a quadrotor flies tilted by its acceleration, and near the tilt limit that
changes q_n by 4-15 % (median, docs/flight.md "What the level attitude costs"). The back end
can therefore correct the level SOLM along the flight it plans: it samples the flight (as
flown, after time scaling) every half cell, casts the SOLM's sensor there at the flatness
attitude and at level (the same position, yaw, rays, noise stream and metric), and spreads
each sample's ratio tilted / level over the 16 nodes the back end interpolates it from,
with the interpolation's weights (a weighted mean of log ratios per node, shrunk toward the
flight's mean); each node's uncapped cost is multiplied by its ratio to the guidance power,
then capped; then it optimises again from that flight. The correction is held fixed during an optimisation (a
round), so each round's objective stays smooth; nodes the flight no longer passes keep
their last correction, which is the attitude a flight through them would have had."""

from __future__ import annotations

import numpy as np

from lf3pm import _core, libm
from lf3pm.config import DEFAULTS
from lf3pm.flight import Quadrotor
from lf3pm.planner.cost_map import CostLayer
from lf3pm.sensors import as_sensor
from lf3pm.solm.grid import Space

#: Rounds of correction after the level optimisation by default: none. Measured on the first
#: flight study's 24 joint flights (docs/investigations/flight_attitude_rounds.py): one round
#: changes the guidance cost met at the flown attitude by -0.3 % median (-8.5 % to +2.9 %)
#: and takes 1.5 s against 0.1-0.4 s; those flights' attitudes change q_n by 2-4 % median.
#: Ask for rounds where flights tilt more (near the tilt limit: 4-15 %; docs/flight.md).
ATTITUDE_ROUNDS = 0
#: Samples per SOLM cell edge along the flight.
SAMPLES_PER_CELL = 2
#: How many samples' weight the flight's mean log ratio counts for at each node.
PRIOR_WEIGHT = 1.0
#: A sample's ratio is clipped to [1 / RATIO_LIMIT, RATIO_LIMIT]: a view degenerate only
#: when tilted (ratio +inf) sends its nodes to the cap without making them infinite.
RATIO_LIMIT = 100.0


class AttitudeGuidance:
    """Casts ``solm``'s sensor (its rays, stride, noise, seed, metric weights and mount, from
    its attributes) at poses along a flight on ``world`` (a Map, the SOLM's) and corrects
    the cost ``layer`` (the guidance layer the back end reads, of ``power``) by what the
    attitude changes, casting on ``threads`` workers (0: every core)."""

    def __init__(self, solm, world, layer: CostLayer, power: float, threads: int = DEFAULTS.scan.threads):
        from lf3pm.solm.tiles import make_job

        attrs, g = solm.attrs, solm.grid_spec
        if g.space is not Space.R3YAW:
            raise ValueError("the guidance at the planned attitude needs an r3yaw SOLM")
        scan = DEFAULTS.scan.model_copy(update={"noise": attrs["noise"], "seed": attrs["seed"]})
        metric = DEFAULTS.metric.model_copy(update={"w1": attrs["w1"], "association": attrs["association"]})
        layout = DEFAULTS.solm.model_copy(update={"ray_stride": attrs["ray_stride"], "yaw_reuse": False})
        self.mount = np.asarray(attrs["mount"]["matrix"], dtype=np.float64)
        job = make_job(as_sensor(attrs["sensor"]), g, scan, metric, layout, self.mount)
        self.rays, self.params = job.rays, job.params(threads)
        self.world, self.grid, self.layer, self.power = world, g, layer, power
        self.metric = layer.channel
        # The layer before its cap: the channel over its scale to the power (+inf degenerate).
        values = np.asarray(solm.channel(self.metric), dtype=np.float64)
        degenerate = np.asarray(solm.channel("degenerate")).astype(bool)
        self.uncapped = np.where(degenerate, np.inf, libm.power(values / layer.scale, power))
        self.start()

    def start(self) -> None:
        """Forgets every correction: the next :meth:`correct` begins a new flight's."""
        self.log_sum = np.zeros(self.layer.filled.shape)
        self.weight_sum = np.zeros(self.layer.filled.shape)
        self.flight_log_sum, self.flight_samples = 0.0, 0

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
        :func:`sample_rate`, as flown): each node takes the weighted mean of the log ratios
        of the samples interpolated from it, this round's and earlier rounds' together.
        Returns the corrected cost (float64, the layer's shape) and a summary: samples, the
        median ratio and its 5-95 % range, the share of samples whose metric the attitude
        changes by more than 10 % and those degenerate only when tilted (both counted in the
        share)."""
        derivatives = (samples[name] for name in ("velocity", "acceleration", "jerk", "yaw", "yaw_rate"))
        att = quad.attitudes(*derivatives)
        p = samples["position"]
        r = self.ratios(p, att.rotation, samples["yaw"])
        known = ~np.isnan(r)
        nodes, weights = interpolation_nodes(self.grid, p[known], samples["yaw"][known])
        log_ratio = libm.log(np.clip(r[known], 1.0 / RATIO_LIMIT, RATIO_LIMIT))
        np.add.at(
            self.log_sum, np.unravel_index(nodes.ravel(), self.log_sum.shape), (weights * log_ratio[:, None]).ravel()
        )
        np.add.at(self.weight_sum, np.unravel_index(nodes.ravel(), self.weight_sum.shape), weights.ravel())
        self.flight_log_sum += float(np.sum(log_ratio))
        self.flight_samples += len(log_ratio)
        # Every node shrinks toward the flight's mean log ratio, as if it held PRIOR_WEIGHT of
        # a sample at it: a node the flight never passed would tilt as the flight does on
        # average. Without it the correction only penalises (ratio > 1 is the rule) the nodes
        # the flight passed, and pushes the next round onto level-valued neighbours
        # (docs/flight.md). Through the C library (lf3pm.libm): the same plan on every CPU.
        mean = self.flight_log_sum / max(self.flight_samples, 1)
        log_correction = (self.log_sum + PRIOR_WEIGHT * mean) / (self.weight_sum + PRIOR_WEIGHT)
        layer = self.layer
        cost = np.minimum(
            self.uncapped * libm.power(libm.exp(log_correction.ravel()), self.power).reshape(log_correction.shape),
            layer.cap,
        )
        cost = np.where(np.isnan(layer.cost), layer.cap, cost)
        seen = r[known]
        summary = {
            "samples": int(len(r)),
            "ratio_median": float(np.median(seen)) if len(seen) else float("nan"),
            "ratio_p5_p95": [float(x) for x in np.percentile(seen, [5, 95])] if len(seen) else [],
            "changed_over_10_percent": float(np.mean(np.abs(seen - 1.0) > 0.1)) if len(seen) else 0.0,
            "degenerate_only_tilted": int(np.sum(np.isinf(seen))),
        }
        return cost, summary


def interpolation_nodes(grid, positions: np.ndarray, yaws: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The 16 nodes (linear indices into the r3yaw channel's shape) and weights from which
    the back end's guidance field (cpp/lf3pm/flight/volume_field.cpp) interpolates each of
    the n samples at ``positions`` (n x 3) and ``yaws`` (n): x and y between cell centres,
    z between levels (uniformly spaced), yaw periodically between bins, clamped at the
    grid's edges. Returns (n, 16) indices and weights (each row sums to 1)."""
    levels = np.asarray(grid.z_levels, dtype=np.float64)
    dz = float(np.diff(levels).mean()) if len(levels) > 1 else grid.res

    def axis(v, origin, step, n):
        if n < 2:
            zero = np.zeros(len(v), dtype=np.int64)
            return zero, zero, np.zeros(len(v))
        f = np.clip((v - origin) / step, 0.0, n - 1.0)
        i0 = np.minimum(np.floor(f).astype(np.int64), n - 2)
        return i0, i0 + 1, f - i0

    ix = axis(positions[:, 0], grid.x0 + 0.5 * grid.res, grid.res, grid.nx)
    iy = axis(positions[:, 1], grid.y0 + 0.5 * grid.res, grid.res, grid.ny)
    iz = axis(positions[:, 2], levels[0], dz, len(levels))
    bins = grid.yaw_bins
    fb = np.mod(yaws, 2 * np.pi) / (2 * np.pi / bins)
    b0 = np.floor(fb).astype(np.int64) % bins
    ib = (b0, (b0 + 1) % bins, fb - np.floor(fb) if bins > 1 else np.zeros(len(yaws)))
    nodes, weights = [], []
    for z, wz in ((iz[0], 1 - iz[2]), (iz[1], iz[2])):
        for b, wb in ((ib[0], 1 - ib[2]), (ib[1], ib[2])):
            for y, wy in ((iy[0], 1 - iy[2]), (iy[1], iy[2])):
                for x, wx in ((ix[0], 1 - ix[2]), (ix[1], ix[2])):
                    nodes.append(((z * bins + b) * grid.ny + y) * grid.nx + x)
                    weights.append(wz * wb * wy * wx)
    return np.stack(nodes, axis=1), np.stack(weights, axis=1)


def sample_rate(grid, vmax: float) -> float:
    """Samples a second along a flight so that at the speed limit they fall
    :data:`SAMPLES_PER_CELL` to a cell edge."""
    return SAMPLES_PER_CELL * vmax / grid.res
