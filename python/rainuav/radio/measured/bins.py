"""A log's rows in bins: a pixel wide and a level tall, the unit the residual field is fitted
and conditioned on ([`rainuav.radio.measured.residual`][rainuav.radio.measured.residual]), and
the pooled spread of the rows about their bins' means (one sample's spread)."""

from __future__ import annotations

import numpy as np

__all__ = ["bin_index", "bin_points", "bin_scale", "sample_spread"]


def bin_index(
    x: np.ndarray, y: np.ndarray, h: np.ndarray, size_m: float, step_m: float,
    group: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """The bin each point falls in, and the bins' row counts.

    Args:
        x: East, m (N,).
        y: North, m (N,).
        h: Height, m (N,).
        size_m: The bins' width, m.
        step_m: Their height, m.
        group: Each point's group (N,), kept apart (a cell's bins are not another's); None: one.

    Returns:
        `(bin, count)`: each row's bin (N,) and the bins' row counts (B,).
    """
    cols = [np.floor(x / size_m), np.floor(y / size_m), np.round(h / step_m)]
    if group is not None:
        cols.append(np.asarray(group, dtype=float))
    keys = np.column_stack(cols).astype(np.int64)
    _, inv, count = np.unique(keys, axis=0, return_inverse=True, return_counts=True)
    return inv.ravel(), count


def bin_points(
    x: np.ndarray, y: np.ndarray, h: np.ndarray, v: np.ndarray, size_m: float, step_m: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Values averaged over bins: the bins' mean positions, mean values and row counts.

    Args:
        x: East, m (N,).
        y: North, m (N,).
        h: Height, m (N,).
        v: The values (N,).
        size_m: The bins' width, m.
        step_m: Their height, m.

    Returns:
        `(positions (B, 3), values (B,), counts (B,))`.
    """
    inv, count = bin_index(x, y, h, size_m, step_m)

    def mean(a: np.ndarray) -> np.ndarray:
        return np.bincount(inv, weights=a) / count

    return np.column_stack([mean(x), mean(y), mean(h)]), mean(v), count


def sample_spread(
    x: np.ndarray, y: np.ndarray, h: np.ndarray, v: np.ndarray, size_m: float, step_m: float
) -> float:
    """The pooled standard deviation of values about their bins' means: one sample's spread, dB.

    Args:
        x: East, m (N,).
        y: North, m (N,).
        h: Height, m (N,).
        v: The values, dB (N,).
        size_m: The bins' width, m.
        step_m: Their height, m.

    Returns:
        The spread, dB; NaN where no bin has two rows.
    """
    inv, count = bin_index(x, y, h, size_m, step_m)
    mean = np.bincount(inv, weights=v) / count
    dof = len(v) - len(count)
    if dof < 1:
        return float("nan")
    return float(np.sqrt(np.sum((v - mean[inv]) ** 2) / dof))


def bin_scale(
    pts: np.ndarray, scale: np.ndarray | None, size_m: float, step_m: float, count: np.ndarray
) -> np.ndarray:
    """Each bin's scale: the root mean square of its rows' scales (the residual's "Scaled" field).

    Args:
        pts: The rows' points (N, 3), m.
        scale: Each row's scale (N,); None: ones.
        size_m: The bins' width, m.
        step_m: Their height, m.
        count: The bins' row counts (B,), as `bin_points()` gives them.

    Returns:
        (B,) scales.
    """
    if scale is None:
        return np.ones(len(count))
    inv, _ = bin_index(pts[:, 0], pts[:, 1], pts[:, 2], size_m, step_m)
    return np.sqrt(np.bincount(inv, weights=np.asarray(scale, float) ** 2) / count)
