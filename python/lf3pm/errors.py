"""User-facing errors.

Every mistake a user can make (a missing map, an unknown sensor, a pose outside
the map) raises a subclass of :class:`Lf3pmError` whose message is one line that
names the problem. The CLI prints that line and exits non-zero; it never shows a
traceback for these.
"""


def one_line(text) -> str:
    """``text`` on one line: a newline in a path or a message shown as \\n."""
    return str(text).replace("\r", "\\r").replace("\n", "\\n")


def one_line_warning(message, category=None, filename=None, lineno=None, line=None) -> str:
    """A ``warnings.formatwarning`` for what users read: ``lf3pm: warning: MESSAGE`` on one
    line (:func:`one_line`), without Python's file:line and source line (and no second
    "lf3pm: " where the message names its source already)."""
    return f"lf3pm: warning: {one_line(message).removeprefix('lf3pm: ')}\n"


class Lf3pmError(Exception):
    """Base class of errors caused by user input; the message is one line."""


class CoreInputError(Lf3pmError, ValueError):
    """Input the C++ core refused (its std::invalid_argument, translated by the bindings);
    a ValueError too, so that callers of lf3pm._core may catch either."""


class CoreLevelError(Lf3pmError, ImportError):
    """No build of the compiled core runs on this CPU, or LF3PM_CORE names one that
    was not built or cannot run here."""


class MapError(Lf3pmError):
    """A map file cannot be read or holds no usable points."""


class RunError(MapError):
    """A recorded run (a folder of scans with poses, a ROS bag) cannot be read, or one of
    its scans, messages or poses is unusable; the message names the file, or the topic
    and the message's index or stamp. A MapError too: a run folder is also read as a map."""


class SensorError(Lf3pmError):
    """A sensor name or sensor description is invalid."""


class PoseError(Lf3pmError):
    """A pose is malformed or lies where it cannot be evaluated."""


class StorageError(Lf3pmError):
    """Storage failed under a read or write (a full disk, an I/O error, a folder that
    vanished); the message names the file and says what was kept and how to go on."""


class CorruptStoreError(Lf3pmError):
    """A store's chunk or metadata cannot be decoded; the message names it and says how
    to get a sound store back."""
