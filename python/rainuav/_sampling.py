"""Pixel-centred bilinear sampling of a map (one convention for the whole package).

A map ``values`` (H, W) over ``extent = (x_min, x_max, y_min, y_max)`` holds sample [i, j] at
the pixel centre ``x = x_min + (j + 0.5) (x_max - x_min) / W``,
``y = y_min + (i + 0.5) (y_max - y_min) / H``; between centres it is bilinear, beyond the
outermost centres the edge values hold. Radio maps, rain-rate maps and the SINR field the UAV
flies through all use it, so what the engine writes is what the environment reads.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import numpy.typing as npt

from rainuav import _core


def bilinear(
    values: np.ndarray,
    extent: tuple[float, float, float, float],
    x: npt.ArrayLike,
    y: npt.ArrayLike,
    k: Any = None,
) -> Any:
    """``values`` (H, W) sampled at the points ``(x, y)`` (any broadcastable shapes); with
    ``k``, ``values`` is (K, H, W) and each point reads its own slice ``k``."""
    return _Weights(values.shape[-2:], extent, x, y).mix(values.reshape(-1), k)


def in_time(
    values: np.ndarray,
    extent: tuple[float, float, float, float],
    x: npt.ArrayLike,
    y: npt.ArrayLike,
    k0: Any,
    k1: Any,
    f: Any,
) -> np.ndarray:
    """``values`` (S, H, W) float64 at the points ``(x, y)``, each point between its slices
    ``k0`` and ``k1``: ``(1 - f) bilinear(.., k0) + f bilinear(.., k1)`` (the first alone
    where ``k0 == k1``), every argument broadcast to one shape. One pass in the Rust core
    (``rainuav._core.sample_slices``), operation for operation as `bilinear`. Where
    ``k0``, ``k1`` and ``f`` do not vary along the last axis (one instant per UAV for the
    points of its window, shape (N, 1)) they cross once per row, not once per point."""
    shape = np.broadcast_shapes(*(np.shape(a) for a in (x, y, k0, k1, f)))
    if math.prod(shape) == 0:
        return np.zeros(shape)
    kshape = np.broadcast_shapes(*(np.shape(a) for a in (k0, k1, f)))
    if len(kshape) == len(shape) > 0 and kshape[-1] == 1:
        rows = (*shape[:-1], 1)  # one instant per row
    elif math.prod(kshape) == 1:
        rows = (1,)  # one instant for every point
    else:
        rows = shape

    def flat(a: Any, dtype: type, to: tuple[int, ...]) -> np.ndarray:
        a = np.asarray(a, dtype)
        a = a.reshape(-1) if to == (1,) else np.broadcast_to(a, to)
        return np.ascontiguousarray(a).reshape(-1)

    ext = tuple(float(e) for e in extent)
    xy = (flat(x, np.float64, shape), flat(y, np.float64, shape))
    ks = (flat(k0, np.int64, rows), flat(k1, np.int64, rows), flat(f, np.float64, rows))
    return _core.sample_slices(values, ext, *xy, *ks).reshape(shape)  # type: ignore[arg-type]


class _Weights:
    """The four pixel centres around each point (flat indices within a slice) and the
    bilinear weights, computed once for any number of slices."""

    def __init__(
        self, shape: tuple[int, ...], extent: Any, x: npt.ArrayLike, y: npt.ArrayLike
    ) -> None:
        x0, x1, y0, y1 = extent
        h, w = shape
        fx = np.clip((np.asarray(x, dtype=np.float64) - x0) / (x1 - x0) * w - 0.5, 0.0, w - 1.0)
        fy = np.clip((np.asarray(y, dtype=np.float64) - y0) / (y1 - y0) * h - 0.5, 0.0, h - 1.0)
        j0 = np.minimum(np.floor(fx), max(w - 2, 0)).astype(np.int64)
        i0 = np.minimum(np.floor(fy), max(h - 2, 0)).astype(np.int64)
        self.tx, self.ty = fx - j0, fy - i0
        self.sx, self.sy = 1.0 - self.tx, 1.0 - self.ty
        j1 = np.minimum(j0 + 1, w - 1)
        r0, r1 = i0 * w, np.minimum(i0 + 1, h - 1) * w
        self.corners = (r0 + j0, r0 + j1, r1 + j0, r1 + j1)
        self.size = h * w

    def mix(self, flat: np.ndarray, k: Any = None) -> Any:
        """A map's values, flattened, at the points; or, flattened from (K, H, W), each point
        reading slice ``k``."""
        if k is None:
            c00, c01, c10, c11 = (flat.take(c) for c in self.corners)
        else:
            base = np.asarray(k) * self.size
            c00, c01, c10, c11 = (flat.take(base + c) for c in self.corners)
        tx, ty, sx, sy = self.tx, self.ty, self.sx, self.sy
        return c00 * sx * sy + c01 * tx * sy + c10 * sx * ty + c11 * tx * ty


def pixel_index(
    shape: tuple[int, ...], extent: tuple[float, ...], x: npt.ArrayLike, y: npt.ArrayLike
) -> tuple[Any, Any]:
    """The (row, column) of the pixel holding each point, clamped to the map.

    Args:
        shape: The map's shape (..., H, W).
        extent: `(x_min, x_max, y_min, y_max)`, m.
        x: East, m.
        y: North, m.

    Returns:
        `(rows, columns)`, of the points' shape.
    """
    x0, x1, y0, y1 = extent
    h, w = shape[-2:]
    j = np.clip(np.floor((np.asarray(x, dtype=np.float64) - x0) / (x1 - x0) * w), 0, w - 1)
    i = np.clip(np.floor((np.asarray(y, dtype=np.float64) - y0) / (y1 - y0) * h), 0, h - 1)
    return i.astype(np.int64), j.astype(np.int64)


def lerp_rows(g: np.ndarray, k0: np.ndarray, k1: np.ndarray, f: np.ndarray) -> np.ndarray:
    """Rows ``g[k0]`` and ``g[k1]`` mixed by ``f`` per row, as the fields mix slices."""
    out = g[k0]  # a copy; the rows between two slices are mixed in place
    mix = k0 != k1
    if mix.any():
        fm = f[mix][:, None]
        out[mix] = (1.0 - fm) * out[mix] + fm * g[k1[mix]]
    return out


class PointCache:
    """Samples of every slice at fixed points (a UAV's whole-area grid), kept per points."""

    def __init__(self) -> None:
        self.rows: dict[bytes, np.ndarray] = {}

    def get(self, db: np.ndarray, extent: Any, points: np.ndarray) -> np.ndarray:
        key = points.tobytes()
        if key not in self.rows:
            k = np.arange(int(np.prod(db.shape[:-2])))[:, None]
            flat = db.reshape(-1, *db.shape[-2:])
            vals = bilinear(flat, extent, points[:, 0], points[:, 1], k)
            self.rows[key] = vals.reshape(*db.shape[:-2], len(points))
        return self.rows[key]
