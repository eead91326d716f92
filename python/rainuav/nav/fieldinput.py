"""The checks of a signal field's input and the pixel that holds a point.

One line names the bad array, never a traceback from deep inside; shared by
[`rainuav.nav.field`][rainuav.nav.field] and the flights that read its masks."""

from __future__ import annotations

from typing import Any

import numpy as np
import numpy.typing as npt

from rainuav._checks import as_real_array
from rainuav._sampling import pixel_index
from rainuav.errors import InvalidInputError

__all__ = [
    "checked_altitudes",
    "checked_mask",
    "checked_probability",
    "checked_values",
    "pixel_index",
]


def checked_values(
    values_db: npt.ArrayLike,
    extent_m: Any,
    name: str,
    serving_cell: npt.ArrayLike | None,
    dims: str,
) -> tuple[np.ndarray, tuple[float, float, float, float], np.ndarray | None]:
    """The values, the extent and the serving cells of a field, checked.

    Args:
        values_db: The values, dB, with the axes `dims`.
        extent_m: `(x_min, x_max, y_min, y_max)`, m.
        name: The values' name in the messages.
        serving_cell: The serving cells, of the values' shape; None: none.
        dims: The axes the values must have (`"(H, W)"`, `"(K, L, H, W)"`, ...).

    Returns:
        `(values, extent, serving cells or None)`.

    Raises:
        InvalidInputError: Values of another rank or not finite, an extent that is not four
            increasing bounds, or serving cells of another shape (named).
    """
    ndim = dims.count(",") + 1
    v = np.asarray(values_db, dtype=np.float64)
    if v.ndim != ndim or min(v.shape) < 1:
        raise InvalidInputError(f"{name} must be a {ndim}-D {dims} array (got shape {v.shape})")
    if not np.all(np.isfinite(v)):
        raise InvalidInputError(f"{name} must be finite everywhere (no NaN or inf)")
    e = np.asarray(extent_m, dtype=np.float64)
    if e.shape != (4,) or not np.all(np.isfinite(e)):
        raise InvalidInputError(f"extent_m must be (x_min, x_max, y_min, y_max) (got {extent_m!r})")
    if not (e[1] > e[0] and e[3] > e[2]):
        raise InvalidInputError(
            f"extent_m must have x_max > x_min and y_max > y_min (got {extent_m!r})"
        )
    serving = None
    if serving_cell is not None:
        sv = np.asarray(serving_cell)
        if sv.shape != v.shape:
            raise InvalidInputError(
                f"serving_cell must have the shape of {name}, {v.shape} (got {sv.shape})"
            )
        serving = sv.astype(np.int64)
    extent = (float(e[0]), float(e[1]), float(e[2]), float(e[3]))
    return np.ascontiguousarray(v), extent, serving


def checked_probability(p: npt.ArrayLike, shape: tuple[int, int]) -> np.ndarray:
    """Probabilities of outage, checked.

    Args:
        p: The probabilities.
        shape: The map's (H, W).

    Returns:
        A read-only (H, W) float array.

    Raises:
        InvalidInputError: Another shape, or values outside [0, 1].
    """
    a = np.asarray(p, dtype=np.float64)
    if a.shape != shape or not np.all((a >= 0) & (a <= 1)):
        raise InvalidInputError(
            f"outage_p must be a (H, W) = {shape} array of probabilities in [0, 1] (got {a.shape})"
        )
    a = np.ascontiguousarray(a)
    a.flags.writeable = False
    return a


def checked_mask(mask: npt.ArrayLike, shape: tuple[int, ...]) -> np.ndarray | None:
    """A not-flyable mask, checked.

    Args:
        mask: The mask, or None.
        shape: The map's (H, W), or (L, H, W) among levels.

    Returns:
        A read-only bool array, or None.

    Raises:
        InvalidInputError: Another shape, or values that are not bool or integer.
    """
    if mask is None:
        return None
    m = np.asarray(mask)
    if m.shape != shape or m.dtype.kind not in "bui":
        raise InvalidInputError(
            f"not_flyable must be a {'(L, H, W)' if len(shape) == 3 else '(H, W)'} = {shape} bool "
            f"array (got {m.shape})"
        )
    m = np.ascontiguousarray(m.astype(bool))
    m.flags.writeable = False
    return m


def checked_altitudes(altitudes_m: Any, levels: int) -> np.ndarray:
    """The levels' altitudes, checked: one a level, increasing.

    Args:
        altitudes_m: The altitudes, m.
        levels: The field's levels.

    Returns:
        The altitudes as a float array.

    Raises:
        InvalidInputError: Not one a level, or not increasing.
    """
    alts = as_real_array("altitudes_m", altitudes_m).reshape(-1)
    if alts.size != levels or alts.size == 0:
        raise InvalidInputError(
            f"altitudes_m must hold one altitude a level ({levels} levels, got {alts.size})"
        )
    if alts.size > 1 and not np.all(np.diff(alts) > 0):
        raise InvalidInputError(f"altitudes_m must increase (got {alts.tolist()})")
    return alts
