"""Which rays a sensor returns: :class:`ReturnModel`, the probability that a ray hitting a
surface gives a return, over the hit's range and incidence (the core's ReturnModel,
cpp/lf3pm/scan/return_model.hpp). Fitted from a recorded run by `lf3pm sensors fit`
(lf3pm.audit.sensor_fit.fit_returns); a sensor without one returns every hit."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from lf3pm.errors import SensorError


@dataclass(frozen=True)
class ReturnModel:
    """``probability[i][j]``: the chance of a return from a hit whose range (m) lies in
    ``[range_edges_m[i], range_edges_m[i + 1])`` and whose |cos incidence| lies in
    ``[cos_edges[j], cos_edges[j + 1])``; a value beyond the edges takes the nearest bin.
    Each ray's draw is seeded like its range noise (seed, stream, ray), independently of
    it. Bad tables raise :class:`~lf3pm.errors.SensorError` in one line."""

    range_edges_m: tuple[float, ...]
    cos_edges: tuple[float, ...]
    probability: tuple[tuple[float, ...], ...]

    def __post_init__(self):
        try:
            ranges = tuple(float(v) for v in self.range_edges_m)
            coses = tuple(float(v) for v in self.cos_edges)
            table = tuple(tuple(float(v) for v in row) for row in self.probability)
        except (TypeError, ValueError):
            raise SensorError("return_probability: edges and table must be numbers") from None
        for name, edges in (("range_edges_m", ranges), ("cos_edges", coses)):
            if len(edges) < 2 or not all(math.isfinite(v) for v in edges):
                raise SensorError(f"return_probability: {name} needs at least 2 finite edges")
            if any(b <= a for a, b in zip(edges, edges[1:])):
                raise SensorError(f"return_probability: {name} must increase, got {list(edges)}")
        if coses[0] < 0 or coses[-1] > 1:
            raise SensorError(f"return_probability: cos_edges must lie in [0, 1], got {list(coses)}")
        if len(table) != len(ranges) - 1 or any(len(row) != len(coses) - 1 for row in table):
            raise SensorError(
                f"return_probability: table must have {len(ranges) - 1} rows (range bins) of "
                f"{len(coses) - 1} values (cosine bins)"
            )
        if not all(0.0 <= p <= 1.0 for row in table for p in row):
            raise SensorError("return_probability: every probability must lie in [0, 1]")
        object.__setattr__(self, "range_edges_m", ranges)
        object.__setattr__(self, "cos_edges", coses)
        object.__setattr__(self, "probability", table)

    def at(self, ranges, coses) -> np.ndarray:
        """The return probability of hits at ``ranges`` (m) with |cos incidence| ``coses``
        (the core's lookup, vectorised)."""
        i = np.searchsorted(self.range_edges_m[1:-1], np.asarray(ranges, dtype=np.float64), side="right")
        j = np.searchsorted(self.cos_edges[1:-1], np.asarray(coses, dtype=np.float64), side="right")
        return np.asarray(self.probability)[i, j]

    def to_yaml(self) -> dict:
        """The sensor YAML's ``return_probability`` mapping."""
        return {
            "range_edges_m": list(self.range_edges_m),
            "cos_edges": list(self.cos_edges),
            "table": [list(row) for row in self.probability],
        }

    def core(self):
        """The core's ReturnModel."""
        from lf3pm import _core

        flat = [p for row in self.probability for p in row]
        return _core.ReturnModel(list(self.range_edges_m), list(self.cos_edges), flat)
