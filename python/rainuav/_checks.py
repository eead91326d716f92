"""Argument checking and broadcasting shared by the public modules: every check raises
[`rainuav.InvalidInputError`][rainuav.errors.InvalidInputError] with one line naming the argument
and the allowed range."""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np
import numpy.typing as npt

from rainuav.errors import InvalidInputError

FloatArray = npt.NDArray[np.float64]


def as_real_array(name: str, value: Any) -> FloatArray:
    """``value`` as a float64 array, or an error naming ``name``."""
    if isinstance(value, (str, bytes)) or np.iscomplexobj(value):
        raise InvalidInputError(f"{name} must be real numbers (got {value!r})")
    try:
        return np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError) as err:
        raise InvalidInputError(f"{name} must be real numbers (got {value!r})") from err


def as_real_scalar(name: str, value: Any) -> float:
    """``value`` as a Python float, or an error naming ``name``."""
    arr = as_real_array(name, value)
    if arr.ndim != 0:
        raise InvalidInputError(f"{name} must be a scalar (got shape {arr.shape})")
    return float(arr)


def broadcast_flat(**named: Any) -> tuple[tuple[int, ...], list[FloatArray]]:
    """Broadcasts the named arguments together and returns the common shape and each
    argument as a flat C-contiguous float64 array (no copy when already so)."""
    arrays = {k: as_real_array(k, v) for k, v in named.items()}
    try:
        parts = np.broadcast_arrays(*arrays.values())
    except ValueError as err:
        shapes = ", ".join(f"{k} {a.shape}" for k, a in arrays.items())
        raise InvalidInputError(f"shapes do not broadcast: {shapes}") from err
    shape = parts[0].shape
    return shape, [np.ascontiguousarray(p).reshape(-1) for p in parts]


def check_choice(name: str, value: Any, allowed: tuple[str, ...]) -> str:
    """``value`` if it is one of ``allowed``, else an error listing them."""
    if not isinstance(value, str) or value not in allowed:
        choices = ", ".join(repr(a) for a in allowed)
        raise InvalidInputError(f"{name} must be one of {choices} (got {value!r})")
    return value


def check_number(where: str, value: Any, lo: float, hi: float, unit: str = "") -> float:
    """``value`` as a float if it is a finite number within ``lo..hi``, else an error naming
    ``where`` and the range."""
    if isinstance(value, bool):
        raise InvalidInputError(f"{where} must be a number (got {value!r})")
    try:
        v = float(value)
    except (TypeError, ValueError) as err:
        raise InvalidInputError(f"{where} must be a number (got {value!r})") from err
    if not (math.isfinite(v) and lo <= v <= hi):
        raise InvalidInputError(f"{where} must be within {lo:g}..{hi:g}{unit} (got {value!r})")
    return v


MEMORY_SHARE = 0.8
"""A job may use at most this share of the memory the machine reports as available (the same
rule as the Rust core's ``check_memory``)."""


def check_fits(what: str, nbytes: float, hint: str) -> None:
    """Refuses, before anything is allocated, a job whose arrays need ``nbytes`` when that is
    over `MEMORY_SHARE` of the available memory: one line naming ``what`` sets the size,
    the GB needed and available, and ``hint`` (how to shrink it)."""
    from rainuav import _core

    avail = _core.available_memory_bytes()
    if avail is not None and nbytes > MEMORY_SHARE * avail:
        raise InvalidInputError(
            f"{what} needs {nbytes / 1e9:.3g} GB but this machine has {avail / 1e9:.3g} GB "
            f"available (at most {MEMORY_SHARE:.0%} may be used); {hint}"
        )


def check_integer(where: str, value: Any, lo: int, hi: int) -> int:
    """``value`` as an int if it is an integer (not a bool, not a float) within ``lo..hi``,
    else an error naming ``where`` and the range."""
    ok = isinstance(value, int | np.integer) and not isinstance(value, bool | np.bool_)
    if not ok or not lo <= int(value) <= hi:
        raise InvalidInputError(f"{where} must be an integer in {lo}..{hi} (got {value!r})")
    return int(value)


_KINDS = {"int": (int,), "float": (int, float), "str": (str,), "bool": (bool,)}


def field_kind(f: dataclasses.Field) -> tuple[str, bool]:
    """The kind of a dataclass field (``"int"``, ``"float"``, ``"str"``, ``"bool"``, or the
    annotation's text for anything else) and whether it may be None (``X | None``). The
    annotations are strings (``from __future__ import annotations``)."""
    kinds = str(f.type).replace(" ", "").split("|")
    return kinds[0], "None" in kinds


def check_field_kinds(obj: Any, prefix: str = "", only: type | None = None) -> None:
    """Each field of the dataclass ``obj`` (of the dataclass ``only``, where given) holds its
    annotated kind (``X | None`` may be None; a bool is not a number); a TOML file or a
    caller can hand in anything."""
    for f in dataclasses.fields(only or obj):
        value = getattr(obj, f.name)
        kind, optional = field_kind(f)
        allowed = _KINDS.get(kind)
        if allowed is None or (value is None and optional):
            continue
        if not isinstance(value, allowed) or (kind != "bool" and isinstance(value, bool)):
            raise InvalidInputError(f"{prefix}{f.name} must be {kind} (got {value!r})")
