"""Checkpoints and policy files that are data, never code.

A run folder is something people hand each other, so loading one must not run anything it holds.
Files are written by [`save()`][rainuav.rl.checkpoint.save] with tensors and plain types only
(numbers, strings, lists, tuples, dicts, None): a numpy array is stored as ``{"__ndarray__":
tensor}`` (a numpy scalar as a 0-d one) and restored bit for bit by
[`load()`][rainuav.rl.checkpoint.load], which reads with ``torch.load(..., weights_only=True)``:
torch's restricted unpickler, which builds tensors and plain containers and refuses any other
global. A file that needs more (a pickle that would call a function, a class, an older checkpoint
holding raw numpy objects) or that is not a checkpoint at all (empty, truncated, random bytes) is
refused with one line naming the file.

Nothing non-finite is saved or loaded: a floating-point tensor or array holding a NaN or an
infinity (a diverged training's weights) makes [`save()`][rainuav.rl.checkpoint.save] raise
[`TrainingDivergedError`][rainuav.errors.TrainingDivergedError] before anything is written, and
[`load()`][rainuav.rl.checkpoint.load] refuse the file, naming the entry."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import numpy as np
import torch

from rainuav._io import write_atomic
from rainuav.errors import InvalidInputError, TrainingDivergedError

__all__ = ["from_plain", "load", "non_finite", "save", "to_plain"]

_ARRAY = "__ndarray__"


def to_plain(obj: Any) -> Any:
    """An object with every numpy array or scalar replaced by `{"__ndarray__": tensor}`.

    Containers are copied; tensors and plain values pass through.

    Args:
        obj: A run's state.

    Returns:
        What `torch.save` writes and `weights_only=True` reads back.

    Raises:
        TypeError: A numpy object array (a checkpoint holds no code).
    """
    if isinstance(obj, np.ndarray | np.generic):
        arr = np.asarray(obj)
        if arr.dtype == object:
            raise TypeError("a checkpoint cannot hold numpy object arrays")
        return {_ARRAY: torch.from_numpy(np.array(arr, order="C", copy=True))}
    if isinstance(obj, dict):
        return {k: to_plain(v) for k, v in obj.items()}
    if isinstance(obj, list):
        return [to_plain(v) for v in obj]
    if isinstance(obj, tuple):
        return tuple(to_plain(v) for v in obj)
    return obj


def from_plain(obj: Any) -> Any:
    """The inverse of `to_plain()`: 0-d arrays come back as numpy scalars.

    Args:
        obj: What [`load()`][rainuav.rl.checkpoint.load] read.

    Returns:
        The state with its numpy arrays.
    """
    if isinstance(obj, dict):
        if set(obj) == {_ARRAY} and isinstance(obj[_ARRAY], torch.Tensor):
            arr = obj[_ARRAY].numpy()
            return arr[()] if arr.ndim == 0 else arr
        return {k: from_plain(v) for k, v in obj.items()}
    if isinstance(obj, list):
        return [from_plain(v) for v in obj]
    if isinstance(obj, tuple):
        return tuple(from_plain(v) for v in obj)
    return obj


def non_finite(obj: Any, where: str = "") -> str | None:
    """The first floating-point tensor or array of a state holding a NaN or an infinity.

    Plain numbers are a run's records, not weights, and are not checked.

    Args:
        obj: The state.
        where: The dotted name of `obj` itself.

    Returns:
        Its dotted name, or None where every one is finite.
    """
    if isinstance(obj, torch.Tensor):
        if obj.is_floating_point() or obj.is_complex():
            return None if bool(torch.isfinite(obj).all()) else where or "the value"
        return None
    if isinstance(obj, np.ndarray | np.generic):
        a = np.asarray(obj)
        if np.issubdtype(a.dtype, np.inexact) and not np.isfinite(a).all():
            return where or "the value"
        return None
    if isinstance(obj, dict):
        items: Any = obj.items()
    elif isinstance(obj, list | tuple):
        items = enumerate(obj)
    else:
        return None
    for k, v in items:
        got = non_finite(v, f"{where}.{k}" if where else str(k))
        if got is not None:
            return got
    return None


def save(path: str | os.PathLike[str], state: dict[str, Any]) -> Path:
    """Writes a state (tensors, numpy arrays and plain values) atomically.

    Args:
        path: The file.
        state: The state.

    Returns:
        The path written.

    Raises:
        TrainingDivergedError: A tensor or array that is not finite (nothing is written).
    """
    bad = non_finite(state)
    if bad is not None:
        raise TrainingDivergedError(
            f"{Path(path).name}: not written: {bad} holds NaN or infinite values (the training "
            "diverged: lower dqn.lr, keep dqn.grad-clip above 0, or use the huber loss)"
        )
    plain = to_plain(state)
    return write_atomic(path, lambda tmp: torch.save(plain, tmp))


def load(
    path: str | os.PathLike[str], required: tuple[str, ...] = (), what: str = "checkpoint"
) -> dict[str, Any]:
    """A state saved by [`save()`][rainuav.rl.checkpoint.save], read without running code.

    Read with `weights_only=True`, on the CPU.

    Args:
        path: The file.
        required: The keys it must hold.
        what: What the errors call the file ("checkpoint", "policy").

    Returns:
        The state.

    Raises:
        InvalidInputError: A file missing, unreadable, not a checkpoint, holding more than tensors
            and plain data, holding values that are not finite, or lacking a required key.
    """
    p = Path(path)
    if not p.is_file():
        raise InvalidInputError(f"{what} {p}: no such file")
    try:
        state = torch.load(p, weights_only=True, map_location="cpu")
    except Exception as err:  # torch raises many types for a bad file; all mean the same
        raise InvalidInputError(f"{what} {p}: refused ({_reason(err)})") from err
    if not isinstance(state, dict):
        raise InvalidInputError(f"{what} {p}: refused (holds a {type(state).__name__}, not a dict)")
    missing = [k for k in required if k not in state]
    if missing:
        raise InvalidInputError(
            f"{what} {p}: refused (no {missing[0]!r}; not written by this rainuav version?)"
        )
    bad = non_finite(state)
    if bad is not None:
        raise InvalidInputError(
            f"{what} {p}: refused ({bad} holds NaN or infinite values: a diverged training's)"
        )
    return from_plain(state)


def _reason(err: Exception) -> str:
    """One line for why torch could not load a file."""
    text = str(err)
    if "Unsupported global" in text or "GLOBAL" in text:
        name = text.split("GLOBAL ", 1)[1].split(" ", 1)[0] if "GLOBAL " in text else "a global"
        return (
            f"its pickle calls {name}: it holds more than tensors and plain data, so loading "
            "it could run code, and rainuav never loads such files"
        )
    if isinstance(err, EOFError) or "EOF" in text or "truncated" in text.lower():
        return "empty or truncated file"
    if "central directory" in text or "zip archive" in text or "Unsupported operand" in text:
        return "not a torch checkpoint, or a damaged one"
    first = text.strip().splitlines()[0] if text.strip() else ""
    return f"not a torch checkpoint: {type(err).__name__}: {first[:120]}"
