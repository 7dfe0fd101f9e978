"""A piecewise-cubic (x, y, yaw) trajectory, as the MINCO back end produces it."""

from __future__ import annotations

import io
from dataclasses import dataclass

import numpy as np

from lf3pm import _core
from lf3pm.atomic import atomic_write
from lf3pm.errors import Lf3pmError
from lf3pm.limits import MAX_TRAJECTORY_BYTES, check_file

CSV_COLUMNS = ("t", "x", "y", "yaw", "vx", "vy", "omega")
#: Samples per second of a trajectory CSV (and of a Trajectory replayed directly, so that
#: both replay the same motion), of a plan's summary and of the limit checks.
CSV_RATE = 100.0
#: The most samples :meth:`Trajectory.sample` returns: 10 M at 100 Hz is 28 h of motion.
MAX_SAMPLES = 10_000_000


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
        piece, tau = self._locate(t)
        c = self.coefficients[piece]  # (n, 4, 3)
        p, v = _powers(c, tau, 0), _powers(c, tau, 1)
        if self.flat is not None and np.any(self.flat[piece]):
            f = np.asarray(self.flat)[piece]
            yaw, omega = _core.travel_heading(np.ascontiguousarray(c), tau, self.durations[piece])
            yaw += 2 * np.pi * np.round((p[:, 2] - yaw) / (2 * np.pi))
            p[f, 2], v[f, 2] = yaw[f], omega[f]
        return p, v

    def acceleration(self, t) -> np.ndarray:
        """World-frame accelerations (n, 2) (x'', y'') at times t, clamped to [0, duration]."""
        t = np.clip(np.atleast_1d(np.asarray(t, dtype=np.float64)), 0.0, self.duration)
        piece, tau = self._locate(t)
        return _powers(self.coefficients[piece], tau, 2)[:, :2]

    def sample(self, rate: float = CSV_RATE) -> dict:
        """Samples at ``rate`` Hz from 0 to the end (the end included): dict of arrays
        t, x, y, yaw, vx, vy, omega, ax, ay (world frame)."""
        if not rate > 0:
            raise Lf3pmError(f"sample rate must be positive, got {rate}")
        if self.duration * rate > MAX_SAMPLES:
            raise Lf3pmError(
                f"a trajectory of {self.duration:.3g} s has more than {MAX_SAMPLES:,} samples at "
                f"{rate:g} Hz: check the robot's limits"
            )
        t = np.arange(0.0, self.duration, 1.0 / rate)
        t = np.append(t, self.duration) if t[-1] < self.duration else t
        p, v = self.evaluate(t)
        a = self.acceleration(t)
        return {
            "t": t,
            "x": p[:, 0],
            "y": p[:, 1],
            "yaw": p[:, 2],
            "vx": v[:, 0],
            "vy": v[:, 1],
            "omega": v[:, 2],
            "ax": a[:, 0],
            "ay": a[:, 1],
        }

    def time_scaled(self, factor: float) -> Trajectory:
        """The same path traversed ``factor`` times slower (factor > 0): position at t is
        this trajectory's at t / factor, so speeds and rates scale by 1 / factor and
        accelerations by 1 / factor^2; a flat piece's heading is unchanged."""
        if not (np.isfinite(factor) and factor > 0):
            raise Lf3pmError(f"time scale factor must be a positive number, got {factor}")
        # Coefficient k of a cubic in t / factor: Python's powers (the C library's), as NumPy's
        # vector power differs in the last bit between CPUs (lf3pm.libm).
        scale = np.array([float(factor) ** -k for k in range(4)])
        return Trajectory(self.coefficients * scale[None, :, None], self.durations * factor, self.flat)

    def _locate(self, t: np.ndarray):
        """Piece index and local time of each (clamped) time."""
        starts = np.concatenate([[0.0], np.cumsum(self.durations)[:-1]])
        piece = np.clip(np.searchsorted(starts, t, side="right") - 1, 0, self.pieces - 1)
        return piece, t - starts[piece]

    def to_csv(self, path, rate: float = CSV_RATE) -> None:
        """Write :meth:`csv_bytes` to ``path`` (atomically)."""
        with atomic_write(path) as fp:
            fp.write(self.csv_bytes(rate))

    def csv_bytes(self, rate: float = CSV_RATE) -> bytes:
        """:meth:`sample` as CSV with header ``t,x,y,yaw,vx,vy,omega``."""
        s = self.sample(rate)
        buf = io.StringIO()
        np.savetxt(
            buf,
            np.column_stack([s[c] for c in CSV_COLUMNS]),
            delimiter=",",
            fmt="%.9g",
            header=",".join(CSV_COLUMNS),
            comments="",
        )
        return buf.getvalue().encode()


def _powers(c, tau, order: int):
    """The ``order``-th derivative of the pieces c (n, 4, 3) at times tau (n,), by Horner's
    rule: products and sums in a fixed order, the same on every CPU (einsum's and
    power's vector kernels differ with it)."""
    t = tau[:, None]
    if order == 0:
        return c[:, 0] + t * (c[:, 1] + t * (c[:, 2] + t * c[:, 3]))
    if order == 1:
        return c[:, 1] + t * (2.0 * c[:, 2] + t * (3.0 * c[:, 3]))
    return 2.0 * c[:, 2] + t * (6.0 * c[:, 3])


def read_csv(path, columns: tuple[str, ...] = CSV_COLUMNS, what: str = "trajectory") -> dict:
    """Reads a trajectory CSV as :meth:`Trajectory.to_csv` writes it: a header naming
    at least the ``columns`` (default ``t,x,y,yaw,vx,vy,omega``; any order, extra columns
    ignored), then one row of numbers per sample. Returns a dict of float64
    arrays by column name. Raises Lf3pmError, naming the line, for a missing
    or unreadable file, one that is not a regular file of at most
    limits.MAX_TRAJECTORY_BYTES, a missing column, a row of the wrong length, a field
    that is not a number, a non-finite value, fewer than 2 rows or times that
    do not increase strictly; ``what`` names the file in them."""
    check_file(path, what, limit=MAX_TRAJECTORY_BYTES)
    try:
        with open(path, encoding="utf-8") as fp:
            lines = fp.read().splitlines()
    except (OSError, UnicodeDecodeError) as err:
        raise Lf3pmError(f"{path}: cannot read the {what} ({getattr(err, 'strerror', None) or err})") from None
    lines = [(n, line) for n, line in enumerate(lines, start=1) if line.strip()]
    if not lines:
        raise Lf3pmError(f"{path}: empty file, expected a header {','.join(columns)}")
    header = [name.strip() for name in lines[0][1].split(",")]
    missing = [c for c in columns if c not in header]
    if missing:
        raise Lf3pmError(f"{path}: the header lacks the column(s) {', '.join(missing)} (expected {','.join(columns)})")
    rows = []
    for n, line in lines[1:]:
        fields = line.split(",")
        if len(fields) != len(header):
            raise Lf3pmError(f"{path}:{n}: {len(fields)} fields, the header has {len(header)}")
        try:
            rows.append([float(f) for f in fields])
        except ValueError:
            raise Lf3pmError(f"{path}:{n}: a field is not a number: {line.strip()[:80]!r}") from None
    if len(rows) < 2:
        raise Lf3pmError(f"{path}: {len(rows)} sample(s); a {what} needs at least 2")
    table = np.asarray(rows, dtype=np.float64)
    used = [header.index(c) for c in columns]
    bad = ~np.isfinite(table[:, used])
    if bad.any():
        r, c = np.argwhere(bad)[0]
        raise Lf3pmError(f"{path}:{lines[1 + r][0]}: {columns[c]} is not finite ({table[r, used[c]]})")
    out = {c: table[:, header.index(c)].copy() for c in columns}
    step = np.diff(out["t"])
    if np.any(step <= 0):
        r = int(np.argmax(step <= 0)) + 1
        raise Lf3pmError(
            f"{path}:{lines[1 + r][0]}: time {out['t'][r]:g} does not follow "
            f"{out['t'][r - 1]:g}: times must increase strictly"
        )
    return out
