"""The exceptions rainuav raises. Everything derives from
[`RainuavError`][rainuav.errors.RainuavError]; bad input also derives from `ValueError`, so ``except
ValueError`` keeps working."""

from __future__ import annotations


class RainuavError(Exception):
    """Base class of every error rainuav raises on purpose."""


class InvalidInputError(RainuavError, ValueError):
    """An argument is out of range, of the wrong shape or not a known name.

    The message names the argument and the allowed range."""


class TrainingDivergedError(InvalidInputError):
    """A training's loss, weights or returns stopped being finite: the message names the step
    and the settings that usually cause it; nothing non-finite was saved."""


class WriteError(RainuavError, OSError):
    """A file could not be written (a full disk, a folder that is not writable): the message
    names the file, the reason and the free space; the earlier copy of the file is kept."""


class CacheWarning(UserWarning):
    """The radio-map cache could not be read or written (a read-only or invalid
    ``RAINUAV_CACHE_DIR``, a full disk): the map is still built, returned and written where
    asked; it is only not kept for next time."""
