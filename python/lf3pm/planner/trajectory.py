"""A piecewise-cubic (x, y, yaw) trajectory, as the MINCO back end produces it."""

from __future__ import annotations

import io
from dataclasses import dataclass

import numpy as np

from lf3pm.atomic import atomic_write
from lf3pm.errors import Lf3pmError

CSV_COLUMNS = ("t", "x", "y", "yaw", "vx", "vy", "omega")


@dataclass(frozen=True)
class Trajectory:
    """N cubic pieces: ``coefficients`` (N, 4, 3), piece i is sum_k c[i, k] t^k for t in
    [0, durations[i]], columns x, y, yaw (yaw unwrapped, continuous); world frame.

    ``flat`` (N bools, default none): on those pieces the yaw is the direction of
    travel, atan2(ydot, xdot) (diff and car robots: no lateral motion), and the yaw
    column only picks the turn it is unwrapped to; where the robot is at rest, the
    direction it starts or stops moving in."""

    coefficients: np.ndarray
    durations: np.ndarray
    flat: np.ndarray | None = None

    @property
    def duration(self) -> float:
        """Total duration (s)."""
        return float(np.sum(self.durations))

    @property
    def pieces(self) -> int:
        return len(self.durations)

    def evaluate(self, t):
        """Positions (n, 3) and velocities (n, 3) (x, y, yaw and their rates) at times t,
        clamped to [0, duration]."""
        t = np.clip(np.atleast_1d(np.asarray(t, dtype=np.float64)), 0.0, self.duration)
        starts = np.concatenate([[0.0], np.cumsum(self.durations)[:-1]])
        piece = np.clip(np.searchsorted(starts, t, side="right") - 1, 0, self.pieces - 1)
        tau = t - starts[piece]
        c = self.coefficients[piece]  # (n, 4, 3)
        p, v = _powers(c, tau, 0), _powers(c, tau, 1)
        if self.flat is not None and np.any(self.flat[piece]):
            f = np.asarray(self.flat)[piece]
            # Heading from a time nudged off the ends of a piece, where the robot may be at rest.
            eps = 1e-6 * self.durations[piece]
            tn = np.clip(tau, eps, self.durations[piece] - eps)
            vn, an = _powers(c, tn, 1), _powers(c, tn, 2)
            yaw = np.arctan2(vn[:, 1], vn[:, 0])
            yaw += 2 * np.pi * np.round((p[:, 2] - yaw) / (2 * np.pi))
            omega = (vn[:, 0] * an[:, 1] - vn[:, 1] * an[:, 0]) / np.maximum(np.sum(vn[:, :2] ** 2, axis=1), 1e-300)
            p[f, 2], v[f, 2] = yaw[f], omega[f]
        return p, v

    def sample(self, rate: float = 100.0) -> dict:
        """Samples at ``rate`` Hz from 0 to the end (the end included): dict of arrays
        t, x, y, yaw, vx, vy, omega (world frame)."""
        if not rate > 0:
            raise Lf3pmError(f"sample rate must be positive, got {rate}")
        t = np.arange(0.0, self.duration, 1.0 / rate)
        t = np.append(t, self.duration) if t[-1] < self.duration else t
        p, v = self.evaluate(t)
        return {"t": t, "x": p[:, 0], "y": p[:, 1], "yaw": p[:, 2], "vx": v[:, 0], "vy": v[:, 1],
                "omega": v[:, 2]}

    def to_csv(self, path, rate: float = 100.0) -> None:
        """Write :meth:`sample` as CSV with header ``t,x,y,yaw,vx,vy,omega`` (atomically)."""
        s = self.sample(rate)
        buf = io.StringIO()
        np.savetxt(buf, np.column_stack([s[c] for c in CSV_COLUMNS]), delimiter=",", fmt="%.9g",
                   header=",".join(CSV_COLUMNS), comments="")
        with atomic_write(path) as fp:
            fp.write(buf.getvalue().encode())


def _powers(c, tau, order: int):
    """The ``order``-th derivative of the pieces c (n, 4, 3) at times tau (n,)."""
    if order == 0:
        basis = [np.ones_like(tau), tau, tau**2, tau**3]
    elif order == 1:
        basis = [np.zeros_like(tau), np.ones_like(tau), 2 * tau, 3 * tau**2]
    else:
        basis = [np.zeros_like(tau), np.zeros_like(tau), np.full_like(tau, 2.0), 6 * tau]
    return np.einsum("nk,nkd->nd", np.stack(basis, axis=1), c)
