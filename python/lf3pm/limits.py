"""Bounds on what lf3pm reads from a user's text files (``--config FILE.yaml``, sensor
YAML files) and on what its errors quote of them.

A file is read only when it is a regular file (``/dev/zero``, a FIFO or a terminal
would be read without end) of at most :data:`MAX_TEXT_BYTES`. Its YAML is refused
when it nests deeper than :data:`MAX_YAML_DEPTH` or when its aliases expand it to more
than :data:`MAX_YAML_NODES` nodes: an alias costs nothing to parse, but nine levels of
nine aliases stand for 9^9 values, which validating or quoting would walk one by one.
An error quotes at most :data:`EXCERPT` characters of any value (:func:`excerpt`).
"""

from __future__ import annotations

import os
import reprlib
import stat

import yaml

from lf3pm.errors import Lf3pmError

#: The largest config or sensor file read (bytes): the shipped configs are 0.5-1.4 kB and
#: a sensor file of 128 beams about 3 kB; a megabyte is no file a person writes by hand.
MAX_TEXT_BYTES = 1 << 20
#: The largest trajectory CSV read (bytes): an hour (config.MAX_TRAJECTORY_SECONDS) at the
#: 100 Hz `lf3pm plan` writes is 360,000 rows of about 100 characters, 36 MB.
MAX_TRAJECTORY_BYTES = 64 << 20
#: The deepest YAML nesting read: a config is two levels deep, a sensor file two; past a
#: few hundred levels the YAML parser and the validation recurse out of Python's stack.
MAX_YAML_DEPTH = 32
#: The most YAML nodes (scalars, lists, mappings) a document may stand for once every
#: alias is expanded: a config holds about 60, a sensor file of 128 beams about 150.
MAX_YAML_NODES = 100_000
#: The most characters of a value an error quotes.
EXCERPT = 60

_REPR = reprlib.Repr()
_REPR.maxlevel, _REPR.maxlist, _REPR.maxtuple, _REPR.maxdict = 2, 4, 4, 3
_REPR.maxstring = _REPR.maxother = _REPR.maxlong = EXCERPT


def clip(text: str, limit: int = EXCERPT) -> str:
    """``text``, or its first ``limit`` characters and how long it was."""
    return text if len(text) <= limit else f"{text[:limit]}... ({len(text):,} characters)"


def excerpt(value) -> str:
    """repr(``value``), at most about :data:`EXCERPT` characters, built without walking
    the whole value (reprlib: a few items per level, a few levels)."""
    return clip(_REPR.repr(value))


def read_text_file(path, what: str, error: type[Lf3pmError] = Lf3pmError, limit: int = MAX_TEXT_BYTES) -> str:
    """The UTF-8 text of ``path``, a regular file of at most ``limit`` bytes; otherwise
    ``error`` in one line naming the file as ``what`` (e.g. "config")."""
    try:
        # O_NONBLOCK: a FIFO opens at once rather than wait for a writer; it is refused below.
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK)
    except OSError as err:
        raise error(f"{path}: cannot read the {what} ({err.strerror or err})") from None
    try:
        _check_kind(path, os.fstat(fd).st_mode, what, error)
    except Lf3pmError:
        os.close(fd)
        raise
    with os.fdopen(fd, "rb") as fp:
        try:
            data = fp.read(limit + 1)  # the file may grow after fstat
        except OSError as err:
            raise error(f"{path}: cannot read the {what} ({err.strerror or err})") from None
    if len(data) > limit:
        raise error(
            f"{path}: the {what} is larger than {limit:,} bytes, the most lf3pm reads: "
            f"a {what} is a short YAML file (config/*.yaml)"
        )
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError:
        raise error(f"{path}: not a YAML {what} (not UTF-8 text)") from None


def check_file(path, what: str, error: type[Lf3pmError] = Lf3pmError, limit: int = MAX_TEXT_BYTES) -> None:
    """Raises ``error`` in one line unless ``path`` is a regular file of at most ``limit``
    bytes: for a reader that opens the file itself (stat does not wait on a FIFO)."""
    try:
        status = os.stat(path)
    except OSError as err:
        raise error(f"{path}: cannot read the {what} ({err.strerror or err})") from None
    _check_kind(path, status.st_mode, what, error)
    if status.st_size > limit:
        raise error(f"{path}: the {what} is larger than {limit:,} bytes, the most lf3pm reads")


def _check_kind(path, mode: int, what: str, error: type[Lf3pmError]) -> None:
    if not stat.S_ISREG(mode):
        kind = "a directory" if stat.S_ISDIR(mode) else "a device, FIFO or socket"
        raise error(f"{path}: the {what} is {kind}, not a regular file")


class _Loader(yaml.SafeLoader):
    """SafeLoader that refuses nesting deeper than MAX_YAML_DEPTH while composing."""

    def __init__(self, stream):
        super().__init__(stream)
        self.depth = 0

    def compose_node(self, parent, index):
        self.depth += 1
        if self.depth > MAX_YAML_DEPTH:
            raise _Refused(f"YAML nested deeper than {MAX_YAML_DEPTH} levels, the most lf3pm reads: flatten it")
        try:
            return super().compose_node(parent, index)
        finally:
            self.depth -= 1


class _Refused(Exception):
    """A document beyond the limits (the reason)."""


def load_yaml(text: str, name, error: type[Lf3pmError] = Lf3pmError):
    """``yaml.safe_load(text)`` within :data:`MAX_YAML_DEPTH` and :data:`MAX_YAML_NODES`:
    ``error`` in one line naming ``name`` otherwise. A malformed document raises
    yaml.YAMLError, as safe_load does."""
    loader = _Loader(text)
    try:
        node = loader.get_single_node()
        if node is None:
            return None
        _check_expanded_size(node)
        return loader.construct_document(node)
    except _Refused as reason:
        raise error(f"{name}: {reason}") from None
    finally:
        loader.dispose()


def _children(node) -> list:
    if isinstance(node, yaml.SequenceNode):
        return node.value
    if isinstance(node, yaml.MappingNode):
        return [part for pair in node.value for part in pair]
    return []


def _check_expanded_size(root) -> None:
    """Refuses a node graph whose tree, every alias expanded, has more than
    MAX_YAML_NODES nodes, or that refers to itself. Each node is counted once (post-order,
    iterative: a chain of aliases may be longer than Python's stack), so the check
    takes time in the size of the text, not of the expansion."""
    sizes: dict = {}
    open_nodes: set = set()  # started, not finished: the path from the root
    stack = [(root, False)]
    while stack:
        node, finished = stack.pop()
        key = id(node)
        if finished:
            open_nodes.discard(key)
            sizes[key] = 1 + sum(sizes[id(child)] for child in _children(node))
            if sizes[key] > MAX_YAML_NODES:
                raise _Refused(
                    f"YAML whose aliases expand to more than {MAX_YAML_NODES:,} values, the most "
                    "lf3pm reads: write the values out without aliases"
                )
        elif key not in sizes:
            if key in open_nodes:
                raise _Refused("YAML with an alias inside the node it names (a cycle): remove the alias")
            open_nodes.add(key)
            stack.append((node, True))
            stack.extend((child, False) for child in _children(node))
