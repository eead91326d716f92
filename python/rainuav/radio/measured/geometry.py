"""What a pixel's power says about its path: each cell's excess loss over free space from its
antenna, and its distance from the site, at a map's pixels or at any points. The prior's spreads
([`rainuav.radio.measured.prior`][rainuav.radio.measured.prior]) are read by both."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np
import numpy.typing as npt

from rainuav.radio.outputs.sinr import RSS_FLOOR_DBM

if TYPE_CHECKING:  # for the annotations alone
    from rainuav.radio.outputs.mapdata import RadioMap
    from rainuav.radio.scene.scenario import Scenario

__all__ = [
    "excess_at",
    "excess_loss_db",
    "excess_of",
    "free_space_db",
    "site_distance_at",
    "site_distance_m",
]


def excess_at(
    scn: Scenario,
    cell: int,
    x: npt.ArrayLike,
    y: npt.ArrayLike,
    z: npt.ArrayLike,
    power_dbm: npt.ArrayLike,
) -> np.ndarray:
    """The excess loss over free space of a cell's powers at points, dB.

    Args:
        scn: The scenario.
        cell: The cell's index (the map's order).
        x: East, m.
        y: North, m.
        z: Height above sea level, m.
        power_dbm: The cell's power at the points, dBm.

    Returns:
        Free space (with the antenna's gain) less the power, dB; NaN where a power is the floor's.
    """
    from rainuav.radio.measured._view import _cells, _View

    site, c = _cells(scn)[int(cell)]
    v = _View(scn, site, c, x, y, z)
    lam = 299_792_458.0 / scn.freq_hz
    d = np.maximum(np.hypot(v.rho, v.dz), lam)
    fs = c.tx_power_dbm + v.g0 - 20 * np.log10(4 * np.pi * d / lam)
    return excess_of(fs, power_dbm)


def excess_of(free_space_dbm: npt.ArrayLike, power_dbm: npt.ArrayLike) -> np.ndarray:
    """The excess loss of powers over their free-space powers, dB.

    Args:
        free_space_dbm: The free-space powers (with the antenna's gain), dBm.
        power_dbm: The powers, dBm.

    Returns:
        `free_space_dbm - power_dbm`, NaN where a power is the floor's.
    """
    p = np.asarray(power_dbm, dtype=float)
    return np.where(p > RSS_FLOOR_DBM + 1.0, free_space_dbm - p, np.nan)


def site_distance_at(
    scn: Scenario, cell: int, x: npt.ArrayLike, y: npt.ArrayLike, z: npt.ArrayLike
) -> np.ndarray:
    """The distance from a cell's antenna to points, m.

    Args:
        scn: The scenario.
        cell: The cell's index.
        x: East, m.
        y: North, m.
        z: Height above sea level, m.

    Returns:
        The distances, m.
    """
    from rainuav.radio.measured._view import _cells, _View

    site, c = _cells(scn)[int(cell)]
    v = _View(scn, site, c, x, y, z)
    return np.hypot(v.rho, v.dz)


def _pixel_points(
    rm: RadioMap, pixels: npt.ArrayLike
) -> tuple[Any, np.ndarray, np.ndarray, np.ndarray]:
    from rainuav.radio.scene.terrain import flight_heights

    shape = np.shape(rm.rss_dbm)[1:]
    r, c = np.indices(shape) if pixels is None else (np.asarray(pixels[0]), np.asarray(pixels[1]))
    x, y = np.asarray(rm.x_m)[c].ravel(), np.asarray(rm.y_m)[r].ravel()
    z = np.broadcast_to(flight_heights(rm.scenario), shape)[r, c].ravel()
    return (r, c), x, y, z


def free_space_db(rm: RadioMap, pixels: npt.ArrayLike | None = None) -> np.ndarray:
    """Each cell's free-space power with its antenna's gain at a map's pixels, dBm.

    Args:
        rm: The map.
        pixels: `(rows, columns)` to read at alone; None: every pixel.

    Returns:
        (M, H, W), or (M, N) at the `pixels`.
    """
    (r, _), x, y, z = _pixel_points(rm, pixels)
    zero = np.zeros_like(x)
    out = np.stack([excess_at(rm.scenario, k, x, y, z, zero) for k in range(len(rm.rss_dbm))])
    return out.reshape(len(rm.rss_dbm), *np.shape(r))


def excess_loss_db(rm: RadioMap, pixels: npt.ArrayLike | None = None) -> np.ndarray:
    """Each cell's excess loss over free space from its antenna at a map's pixels, dB.

    At the map's flight height (the module of the prior says why the excess loss gives the
    mechanism).

    Args:
        rm: The map.
        pixels: `(rows, columns)` to read at alone; None: every pixel.

    Returns:
        (M, H, W), or (M, N) at the `pixels`; NaN where the cell does not reach.
    """
    (r, c), *_ = _pixel_points(rm, pixels)
    return excess_of(free_space_db(rm, pixels), np.asarray(rm.rss_dbm, dtype=float)[:, r, c])


def site_distance_m(rm: RadioMap, pixels: npt.ArrayLike | None = None) -> np.ndarray:
    """Each cell's distance from its antenna at a map's pixels, at its flight height, m.

    Args:
        rm: The map.
        pixels: `(rows, columns)` to read at alone; None: every pixel.

    Returns:
        (M, H, W), or (M, N) at the `pixels`.
    """
    scn = rm.scenario
    m = len(rm.rss_dbm)
    (r, _), x, y, z = _pixel_points(rm, pixels)
    out = np.stack([site_distance_at(scn, k, x, y, z) for k in range(m)])
    return out.reshape(m, *np.shape(r))
