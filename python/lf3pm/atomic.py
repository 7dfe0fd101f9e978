"""Writing a file so that readers see either the old file or the complete new one."""

from __future__ import annotations

import os
import secrets
import stat
from contextlib import contextmanager, suppress

from lf3pm.errors import Lf3pmError, StorageError


@contextmanager
def atomic_write(path, error: type[Lf3pmError] = StorageError):
    """Yields a binary file whose content replaces ``path`` when the block ends without error.

    The data go to a temporary file in the same directory (so that ``os.replace``
    is a rename within one file system), flushed to disk before the rename. On
    any error the temporary file is removed and ``path`` is left untouched;
    OSErrors (a full disk, an I/O error, a vanished folder) become a one-line ``error``
    (an Lf3pmError subclass) that says so. Only a
    regular file is ever replaced: a rename would put a file in place of a
    symlink, a device or a FIFO (and fails on a directory), so an existing
    ``path`` of any other kind is refused before anything is written.
    """
    check_replaceable(path, error)
    kept = "the existing file is left as it was" if os.path.lexists(path) else "nothing was written"
    directory, base = os.path.split(os.path.abspath(path))
    temporary = os.path.join(directory, f".{base}.{secrets.token_hex(4)}.tmp")
    try:
        # "x" never clobbers a file, and unlike mkstemp keeps the usual umask permissions.
        with open(temporary, "xb") as fp:
            yield fp
            fp.flush()
            os.fsync(fp.fileno())
        os.replace(temporary, path)
    except OSError as err:
        _remove(temporary)
        raise error(f"{path}: cannot write the file ({err.strerror or err}); {kept}") from err
    except BaseException:
        _remove(temporary)
        raise


def check_replaceable(path, error: type[Lf3pmError] = Lf3pmError) -> None:
    """Raises ``error`` when ``path`` exists and is not a regular file."""
    try:
        mode = os.lstat(path).st_mode
    except FileNotFoundError:
        return
    except OSError as err:
        raise error(f"{path}: cannot write the file ({err.strerror or err})") from err
    if not stat.S_ISREG(mode):
        kind = (
            "a directory" if stat.S_ISDIR(mode) else "a symbolic link" if stat.S_ISLNK(mode) else "not a regular file"
        )
        raise error(f"{path} is {kind}: lf3pm replaces only regular files")


def _remove(path: str) -> None:
    """Removes the temporary file if it is there. On storage that refused to create it
    (read-only: EROFS even for a missing file) or has vanished there is nothing to
    remove, and the write's own error is the one to report."""
    with suppress(OSError):
        os.remove(path)
