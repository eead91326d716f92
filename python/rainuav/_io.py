"""Files: writing so that a reader never sees half of one (write beside, then rename), and
reading TOML with one-line errors that name the file."""

from __future__ import annotations

import contextlib
import os
import tempfile
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import tomllib

from rainuav.errors import InvalidInputError


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike[str]) -> Iterator[Path]:
    """Yields a temporary path in the target's directory; on success it replaces ``path``
    in one rename, on failure it is removed and ``path`` is left as it was."""
    target = Path(path)
    target.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=target.parent, prefix=f".{target.name}.", suffix=".tmp")
    os.close(fd)
    tmp_path = Path(tmp)
    try:
        yield tmp_path
        os.replace(tmp_path, target)
    finally:
        tmp_path.unlink(missing_ok=True)


def write_atomic(path: str | os.PathLike[str], write: Callable[[Path], None]) -> Path:
    """Calls ``write(tmp)`` and renames ``tmp`` onto ``path``; returns ``path``."""
    with atomic_path(path) as tmp:
        write(tmp)
    return Path(path)


def read_toml(path: str | os.PathLike[str], what: str = "file") -> dict[str, Any]:
    """The TOML table in ``path``; a missing, unreadable or malformed file raises
    :class:`InvalidInputError` naming ``what``, the file and the problem in one line."""
    p = Path(path)
    try:
        text = p.read_text()
    except FileNotFoundError as err:
        raise InvalidInputError(f"{what} {p}: no such file") from err
    except (OSError, UnicodeDecodeError) as err:
        raise InvalidInputError(f"{what} {p}: cannot be read ({err})") from err
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as err:
        raise InvalidInputError(f"{what} {p}: not valid TOML ({err})") from err
