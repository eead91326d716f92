"""The signal field the UAV flies through: pixel-centred bilinear sampling of a map in dB
(:mod:`rainuav._sampling`), with its input checked once."""

from __future__ import annotations

from typing import Any

import numpy as np
import numpy.typing as npt

from rainuav._sampling import bilinear
from rainuav.errors import InvalidInputError

__all__ = ["SirField"]


class SirField:
    """A SIR (or SINR) map in dB over ``extent_m = (x_min, x_max, y_min, y_max)``, sampled
    bilinearly between pixel centres (:func:`rainuav._sampling.bilinear`)."""

    def __init__(self, sir_db: npt.ArrayLike, extent_m: tuple[float, float, float, float]):
        s = np.asarray(sir_db, dtype=np.float64)
        if s.ndim != 2 or min(s.shape) < 1:
            raise InvalidInputError(f"sir_db must be a 2-D (H, W) array (got shape {s.shape})")
        if not np.all(np.isfinite(s)):
            raise InvalidInputError("sir_db must be finite everywhere (no NaN or inf)")
        e = np.asarray(extent_m, dtype=np.float64)
        if e.shape != (4,) or not np.all(np.isfinite(e)):
            raise InvalidInputError(
                f"extent_m must be (x_min, x_max, y_min, y_max) (got {extent_m!r})"
            )
        if not (e[1] > e[0] and e[3] > e[2]):
            raise InvalidInputError(
                f"extent_m must have x_max > x_min and y_max > y_min (got {extent_m!r})"
            )
        self.sir_db = np.ascontiguousarray(s)
        self.extent = (float(e[0]), float(e[1]), float(e[2]), float(e[3]))

    def __call__(self, x: Any, y: Any) -> Any:
        """The map at the points ``(x, y)`` (bilinear between pixel centres, edge values
        beyond them)."""
        return bilinear(self.sir_db, self.extent, x, y)
