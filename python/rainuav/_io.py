"""Files: writing so that a reader never sees half of one (write beside, then rename), and
reading TOML with one-line errors that name the file."""

from __future__ import annotations

import contextlib
import copy
import dataclasses
import os
import secrets
import shutil
import tempfile
import warnings
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import tomllib

from rainuav.errors import InvalidInputError, WriteError


def _create_beside(target: Path) -> Path:
    """A new empty file next to ``target`` with a unique name, created with mode 0666 less
    the umask, as ``open`` would (``tempfile.mkstemp`` makes 0600 whatever the umask, which
    leaves a shared cache unreadable by colleagues)."""
    for _ in range(100):
        tmp = target.parent / f".{target.name}.{secrets.token_hex(6)}.tmp"
        try:
            fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666)
        except FileExistsError:
            continue
        os.close(fd)
        return tmp
    raise FileExistsError(f"no free temporary name beside {target}")


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike[str]) -> Iterator[Path]:
    """Yields a temporary path in the target's directory; on success it replaces ``path``
    in one rename, on failure it is removed and ``path`` is left as it was."""
    target = Path(path)
    target.parent.mkdir(parents=True, exist_ok=True)
    tmp_path = _create_beside(target)
    try:
        yield tmp_path
        os.replace(tmp_path, target)
    finally:
        tmp_path.unlink(missing_ok=True)


def write_atomic(path: str | os.PathLike[str], write: Callable[[Path], None]) -> Path:
    """Calls ``write(tmp)`` and renames ``tmp`` onto ``path``; returns ``path``. A write that fails
    (torch and numpy report a full disk as ``RuntimeError`` or ``OSError``) raises
    [`WriteError`][rainuav.errors.WriteError] naming the file, the reason and the free space;
    ``path`` is left as it was."""
    try:
        with atomic_path(path) as tmp:
            write(tmp)
    except (OSError, RuntimeError) as err:
        if isinstance(err, WriteError):
            raise
        try:
            free = f"{shutil.disk_usage(Path(path).parent).free / 1e9:.3g} GB free there"
        except OSError:
            free = "free space unknown"
        reason = str(err).splitlines()[0] if str(err) else type(err).__name__
        raise WriteError(
            f"cannot write {path} ({reason}; {free}); its earlier copy, if any, is kept"
        ) from err
    return Path(path)


_NUMBERS = (float, int)


def plain(v: Any) -> Any:
    """A dataclass (or a dict, list or tuple of them) as plain TOML-ready data: what
    ``dataclasses.asdict`` gives, with every field and key that is None left out, and a list of
    plain numbers copied whole rather than one number at a time (a radar weather's half a
    million rates: 0.36 -> 0.07 s)."""
    if dataclasses.is_dataclass(v) and not isinstance(v, type):
        fields = ((f.name, getattr(v, f.name)) for f in dataclasses.fields(v))
        return {k: plain(x) for k, x in fields if x is not None}
    if isinstance(v, dict):
        return {k: plain(x) for k, x in v.items() if x is not None}
    if isinstance(v, list | tuple):  # a named tuple as a plain tuple: TOML has no names there
        items = v if all(type(x) in _NUMBERS for x in v) else [plain(x) for x in v]
        return list(items) if isinstance(v, list) else tuple(items)
    return copy.deepcopy(v)


def read_toml(path: str | os.PathLike[str], what: str = "file") -> dict[str, Any]:
    """The TOML table in ``path``; a missing, unreadable or malformed file raises
    [`InvalidInputError`][rainuav.errors.InvalidInputError] naming ``what``, the file and the
    problem in one line."""
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


def check_out_dir(path: str | os.PathLike[str], flag: str = "--out") -> Path:
    """Checks, before any work, that the output folder ``path`` exists as a writable folder
    or can be made (its nearest existing parent is a writable folder); else raises
    [`InvalidInputError`][rainuav.errors.InvalidInputError] naming ``flag`` and the path. Creates
    nothing that stays.

    Permission bits do not settle it (root passes every ``os.access`` test, and ``/proc`` or
    a read-only mount refuse new folders whatever the bits say), so the check makes an empty
    folder in the nearest existing parent and removes it again."""
    p = Path(path)
    if p.exists() and not p.is_dir():
        raise InvalidInputError(f"{flag} {p}: exists and is not a folder")
    probe = p.absolute()
    while not probe.exists() and probe != probe.parent:
        probe = probe.parent
    if not probe.is_dir():
        raise InvalidInputError(f"{flag} {p}: cannot be created ({probe} is not a folder)")
    if not os.access(probe, os.W_OK | os.X_OK):
        raise InvalidInputError(f"{flag} {p}: not writable ({probe})")
    try:
        os.rmdir(tempfile.mkdtemp(prefix=".rainuav-probe-", dir=probe))
    except OSError as err:
        why = err.strerror or type(err).__name__
        raise InvalidInputError(
            f"{flag} {p}: cannot be written: no folder can be made in {probe} ({why})"
        ) from None
    return p


def begin_folder(folder: str | os.PathLike[str], last: str) -> Path:
    """Makes ``folder`` and removes its completion file ``last`` (left by an earlier run into
    the same folder) before a job writes its files: the job writes ``last`` after every other
    file, so a folder holding ``last`` is complete and one without it was stopped part way
    (a kill -9 included). Returns the folder."""
    out = Path(folder)
    out.mkdir(parents=True, exist_ok=True)
    try:
        (out / last).unlink(missing_ok=True)
    except OSError as err:  # a folder of that name, or a file that cannot be removed
        raise InvalidInputError(
            f"{out / last}: cannot be replaced ({err.strerror or type(err).__name__}); "
            "remove it or use another --out"
        ) from None
    return out


class FolderLock:
    """An exclusive lock on a folder (``flock`` on ``<folder>/.lock``) while a job writes
    into it: a second job on the same folder is refused at once, naming the folder. The
    operating system drops the lock when its process ends, however it ends (kill -9
    included), so a stale lock never blocks a resume."""

    def __init__(self, folder: str | os.PathLike[str], what: str = "a job") -> None:
        self.path = Path(folder) / ".lock"
        self.what = what
        self.fh: Any = None

    def __enter__(self) -> FolderLock:
        import fcntl

        fh = self.path.open("a+")
        try:
            fcntl.flock(fh, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError as err:  # held by another process
            fh.seek(0)
            holder = fh.read().strip() or "another process"
            fh.close()
            raise InvalidInputError(
                f"{self.path.parent}: {holder} is writing to this folder (locked by "
                f"{self.path}); wait for it to end or use another folder"
            ) from err
        except OSError as err:  # a filesystem without locks (some network mounts)
            warnings.warn(
                f"{self.path.parent}: cannot be locked ({err.strerror or err}); make sure no "
                "other job writes to this folder",
                stacklevel=2,
            )
        fh.seek(0)
        fh.truncate()
        fh.write(f"{self.what} (pid {os.getpid()})\n")
        fh.flush()
        self.fh = fh
        return self

    def __exit__(self, *exc: object) -> None:
        if self.fh is not None:
            self.fh.close()  # closing the descriptor releases the lock
            self.fh = None
