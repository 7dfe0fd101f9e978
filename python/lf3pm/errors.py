"""User-facing errors.

Every mistake a user can make (a missing map, an unknown sensor, a pose outside
the map) raises a subclass of :class:`Lf3pmError` whose message is one line that
names the problem. The CLI prints that line and exits non-zero; it never shows a
traceback for these.
"""


import math


class Lf3pmError(Exception):
    """Base class of errors caused by user input; the message is one line."""


def finite_number(name: str, value, *, low: float | None = None, high: float | None = None) -> float:
    """``value`` as a float, or Lf3pmError naming ``name`` when it is not a finite number
    within [low, high] (either bound optional)."""
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise Lf3pmError(f"{name} must be a number, got {value!r}") from None
    if not math.isfinite(number):
        raise Lf3pmError(f"{name} must be finite, got {value}")
    if (low is not None and number < low) or (high is not None and number > high):
        span = f">= {low:g}" if high is None else f"<= {high:g}" if low is None else f"in [{low:g}, {high:g}]"
        raise Lf3pmError(f"{name} must be {span}, got {number:g}")
    return number


class CoreInputError(Lf3pmError, ValueError):
    """Input the C++ core refused (its std::invalid_argument, translated by the bindings);
    a ValueError too, so that callers of lf3pm._core may catch either."""


class MapError(Lf3pmError):
    """A map file cannot be read or holds no usable points."""


class SensorError(Lf3pmError):
    """A sensor name or sensor description is invalid."""


class PoseError(Lf3pmError):
    """A pose is malformed or lies where it cannot be evaluated."""
