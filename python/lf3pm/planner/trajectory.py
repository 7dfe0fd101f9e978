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
    [0, durations[i]], columns x, y, yaw (yaw unwrapped, continuous); world frame."""

    coefficients: np.ndarray
    durations: np.ndarray

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
        powers = np.stack([np.ones_like(tau), tau, tau**2, tau**3], axis=1)
        rates = np.stack([np.zeros_like(tau), np.ones_like(tau), 2 * tau, 3 * tau**2], axis=1)
        return np.einsum("nk,nkd->nd", powers, c), np.einsum("nk,nkd->nd", rates, c)

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
