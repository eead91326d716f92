"""Pixel-centred bilinear sampling of a map (one convention for the whole package).

A map ``values`` (H, W) over ``extent = (x_min, x_max, y_min, y_max)`` holds sample [i, j] at
the pixel centre ``x = x_min + (j + 0.5) (x_max - x_min) / W``,
``y = y_min + (i + 0.5) (y_max - y_min) / H``; between centres it is bilinear, beyond the
outermost centres the edge values hold. Radio maps, rain-rate maps and the SINR field the UAV
flies through all use it, so what the engine writes is what the environment reads.
"""

from __future__ import annotations

from typing import Any

import numpy as np


def bilinear(
    values: np.ndarray, extent: tuple[float, float, float, float], x: Any, y: Any, k: Any = None
) -> Any:
    """``values`` (H, W) sampled at the points ``(x, y)`` (any broadcastable shapes); with
    ``k``, ``values`` is (K, H, W) and each point reads its own slice ``k``."""
    x0, x1, y0, y1 = extent
    h, w = values.shape[-2:]
    fx = np.clip((np.asarray(x, dtype=np.float64) - x0) / (x1 - x0) * w - 0.5, 0.0, w - 1.0)
    fy = np.clip((np.asarray(y, dtype=np.float64) - y0) / (y1 - y0) * h - 0.5, 0.0, h - 1.0)
    j0 = np.minimum(np.floor(fx), max(w - 2, 0)).astype(np.int64)
    i0 = np.minimum(np.floor(fy), max(h - 2, 0)).astype(np.int64)
    tx = fx - j0
    ty = fy - i0
    j1 = np.minimum(j0 + 1, w - 1)
    i1 = np.minimum(i0 + 1, h - 1)
    s = values if k is None else _Slice(values, np.asarray(k))
    return (
        s[i0, j0] * (1.0 - tx) * (1.0 - ty)
        + s[i0, j1] * tx * (1.0 - ty)
        + s[i1, j0] * (1.0 - tx) * ty
        + s[i1, j1] * tx * ty
    )


class _Slice:
    """``values[k, i, j]`` indexed as ``values[i, j]`` (each point its own slice), read as one
    flat ``take`` (several times faster than three index arrays)."""

    def __init__(self, values: np.ndarray, k: np.ndarray) -> None:
        h, w = values.shape[-2:]
        self.flat, self.w = values.reshape(-1), w
        self.base = k * (h * w)

    def __getitem__(self, ij: tuple[Any, Any]) -> Any:
        return self.flat.take(self.base + ij[0] * self.w + ij[1])
