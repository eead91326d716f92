"""The signal field the UAV flies through: pixel-centred bilinear sampling of a map in dB (SINR
or SIR, :mod:`rainuav._sampling`), with its input checked once, and the serving cell at the
nearest pixel when the map names one."""

from __future__ import annotations

from typing import Any

import numpy as np
import numpy.typing as npt

from rainuav._sampling import bilinear
from rainuav.errors import InvalidInputError

__all__ = ["SignalField", "SirField"]


class SignalField:
    """A SINR (or SIR) map in dB over ``extent_m = (x_min, x_max, y_min, y_max)``, sampled
    bilinearly between pixel centres (:func:`rainuav._sampling.bilinear`). ``name`` is the
    array's name in error messages; ``serving_cell`` (H, W), optional, is looked up at the
    nearest pixel."""

    def __init__(
        self,
        values_db: npt.ArrayLike,
        extent_m: tuple[float, float, float, float],
        name: str = "sinr_db",
        serving_cell: npt.ArrayLike | None = None,
    ):
        s = np.asarray(values_db, dtype=np.float64)
        if s.ndim != 2 or min(s.shape) < 1:
            raise InvalidInputError(f"{name} must be a 2-D (H, W) array (got shape {s.shape})")
        if not np.all(np.isfinite(s)):
            raise InvalidInputError(f"{name} must be finite everywhere (no NaN or inf)")
        e = np.asarray(extent_m, dtype=np.float64)
        if e.shape != (4,) or not np.all(np.isfinite(e)):
            raise InvalidInputError(
                f"extent_m must be (x_min, x_max, y_min, y_max) (got {extent_m!r})"
            )
        if not (e[1] > e[0] and e[3] > e[2]):
            raise InvalidInputError(
                f"extent_m must have x_max > x_min and y_max > y_min (got {extent_m!r})"
            )
        self.db = np.ascontiguousarray(s)
        self.name = name
        self.extent = (float(e[0]), float(e[1]), float(e[2]), float(e[3]))
        self.serving: np.ndarray | None = None
        if serving_cell is not None:
            sv = np.asarray(serving_cell)
            if sv.shape != s.shape:
                raise InvalidInputError(
                    f"serving_cell must have the map's shape {s.shape} (got {sv.shape})"
                )
            self.serving = sv.astype(np.int64)

    def __call__(self, x: Any, y: Any) -> Any:
        """The map at the points ``(x, y)`` (bilinear between pixel centres, edge values
        beyond them)."""
        return bilinear(self.db, self.extent, x, y)

    def serving_cell(self, x: Any, y: Any) -> Any:
        """The serving cell at the pixel holding ``(x, y)`` (-1 where the map names none)."""
        x, y = np.asarray(x, dtype=np.float64), np.asarray(y, dtype=np.float64)
        if self.serving is None:
            return np.full(np.broadcast(x, y).shape, -1, dtype=np.int64)
        x0, x1, y0, y1 = self.extent
        h, w = self.db.shape
        j = np.clip(np.floor((x - x0) / (x1 - x0) * w).astype(np.int64), 0, w - 1)
        i = np.clip(np.floor((y - y0) / (y1 - y0) * h).astype(np.int64), 0, h - 1)
        return self.serving[i, j]


SirField = SignalField
"""The old name (the field is whichever signal the task flies on)."""
