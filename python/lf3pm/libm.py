"""Elementwise math through the C library, so that results do not depend on the CPU.

NumPy >= 2 computes float64 arctan2, arcsin, arccos, exp, log and non-trivial powers
(and arctan, tan, log1p, expm1, cbrt, ...) with Intel's SVML on CPUs with AVX-512 and
with the C library elsewhere; the two differ in the last bit for 0.5-8 % of
arguments (NumPy 2.4, measured with NPY_DISABLE_CPU_FEATURES: arctan2 7.8 %, arccos
9.4 %, exp 4.6 %). A scene, a sensor's rays, a SOLM or a plan computed through them
would differ between two machines of one cluster. These functions call the C library
for every element, as Python's math module and the C++ core do: on every x86-64-v3
CPU (FMA), AVX-512 or not, glibc picks the same code (docs/design.md, "Reproducible
builds"). About 0.1 us per element: for the sizes a sensor, a path or a scene's
parameters have, not for a map's points. sin, cos, hypot and sqrt need none of this:
NumPy's are the C library's (sin, cos) or correctly rounded (sqrt, hypot).
"""

from __future__ import annotations

import math

import numpy as np


def _exp(x: float) -> float:
    try:
        return math.exp(x)
    except OverflowError:
        return math.inf


def _log(x: float) -> float:
    # NumPy's values where math raises: log(0) = -inf, log(x < 0) = nan.
    return math.log(x) if x > 0 else (-math.inf if x == 0 else math.nan)


def _pow(x: float, p: float) -> float:
    try:
        return math.pow(x, p)
    except OverflowError:
        return math.inf
    except ValueError:  # 0 to a negative power; a negative base to a fraction
        return math.inf if x == 0 else math.nan


def _clipped(f):
    return lambda x: f(min(max(x, -1.0), 1.0)) if x == x else math.nan


def _elementwise(scalar, arguments: int, doc: str):
    """``scalar`` (math's) applied to every element of float64 arrays (scalars in,
    a float out)."""
    ufunc = np.frompyfunc(scalar, arguments, 1)

    def apply(*values):
        out = ufunc(*(np.asarray(v, dtype=np.float64) for v in values))
        return np.asarray(out, dtype=np.float64) if isinstance(out, np.ndarray) else float(out)

    apply.__doc__ = doc
    return apply


atan2 = _elementwise(math.atan2, 2, "arctan2(y, x) elementwise, through the C library.")
arcsin = _elementwise(_clipped(math.asin), 1, "arcsin(x) elementwise, x clipped to [-1, 1], through the C library.")
arccos = _elementwise(_clipped(math.acos), 1, "arccos(x) elementwise, x clipped to [-1, 1], through the C library.")
exp = _elementwise(_exp, 1, "exp(x) elementwise, through the C library.")
log = _elementwise(_log, 1, "Natural logarithm elementwise (x > 0), through the C library.")
_power = _elementwise(_pow, 2, "")


def power(x, p):
    """x ** p elementwise for x >= 0, through the C library; a scalar p of 1, 2 or 0.5
    is a copy, a square or a square root (exact, so NumPy's are the same everywhere)."""
    if np.ndim(p) == 0 and float(p) in (1.0, 2.0, 0.5):
        out = {1.0: np.copy, 2.0: np.square, 0.5: np.sqrt}[float(p)](np.asarray(x, dtype=np.float64))
        return out if out.ndim else float(out)
    return _power(x, p)
