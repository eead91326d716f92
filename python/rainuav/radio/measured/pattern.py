"""The UAV's receive pattern in elevation, and against its heading, learned from a log.

A map's receiver is isotropic; a real UAV's antenna, under its airframe and its batteries, is
not, and how much it receives from a cell depends on where the cell lies below it. Over a log
flown at several heights the same cell is seen under many elevations, so what the calibrated map
still gets wrong can be split into a gain that depends on that elevation alone, shared by every
cell (the UAV's antenna, the same for all of them), and the rest, which the residual field
takes.

The elevation of a row is the angle from the UAV to the cell's antenna above the horizontal
(negative: the antenna lies below the UAV), degrees. The gain is piecewise linear in it, with
knots every ``STEP_DEG`` over the elevations the log saw, constant beyond them
([`ElevationGain`][rainuav.radio.measured.pattern.ElevationGain]). It is fitted by least squares
with a penalty on its second differences (``SMOOTHING`` times the rows: a smooth pattern, and
a knot the log barely saw follows its neighbours) and a small ridge.

It is asked for (``correct_map(..., receive_pattern="elevation")``, ``radiomap
--receive-pattern elevation``), not assumed: the held-out scores then fit it in every fold, and
say whether it lowered the error. On AERPAW's flights it lowers the calibrated map's held-out
RMSE by 0.5-0.7 dB and raises the corrected map's by 0.1-0.2 dB (the residual field already
takes the trend with height), so it is off by default (the page "How far to trust a map").

**Against the heading.** Where the log has the UAV's heading (``heading_deg``), the airframe's
shadow is a gain by the azimuth under which the UAV sees the cell relative to its nose,
``phi = bearing to the cell - heading``: a Fourier series of ``HARMONICS`` orders without a
constant (the power offset takes that), ``g(phi) = sum_k a_k cos k phi + b_k sin k phi``,
fitted by least squares with a small ridge, shared by every cell
([`HeadingGain`][rainuav.radio.measured.pattern.HeadingGain]). A map does not know which way
the UAV will point at a pixel, so on the map the gain is a spread, not a shift: its root mean
square over the heading, ``sqrt(sum_k (a_k^2 + b_k^2) / 2)``, added to one sample's spread in
quadrature. Asked for as ``receive_pattern="heading"`` (or ``"both"``), like the elevation's;
the held-out scores predict each held-out row with its own heading."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
import numpy.typing as npt

if TYPE_CHECKING:  # for the annotations alone
    from rainuav.radio.scene.scenario import Scenario

__all__ = [
    "HARMONICS",
    "SMOOTHING",
    "STEP_DEG",
    "ElevationGain",
    "HeadingGain",
    "elevation_deg",
    "fit_gain",
    "fit_heading_gain",
    "relative_azimuth_deg",
]

STEP_DEG = 5.0
"""The knots' spacing, degrees."""
SMOOTHING = 1e-3
"""The second differences' penalty, per row."""
HARMONICS = 2
"""The orders of the heading gain's Fourier series."""


@dataclass(frozen=True)
class ElevationGain:
    """A receive gain by elevation, dB, piecewise linear between knots, constant beyond."""

    knots_deg: np.ndarray
    """The knots' elevations, degrees, increasing."""
    gain_db: np.ndarray
    """The gain at each knot, dB."""

    def at(self, elevation_deg: npt.ArrayLike) -> np.ndarray:
        """The gain at elevations, dB.

        Args:
            elevation_deg: Elevations, degrees.

        Returns:
            The gain, dB.
        """
        return np.interp(np.asarray(elevation_deg, dtype=float), self.knots_deg, self.gain_db)

    def to_dict(self) -> dict[str, list[float]]:
        """The gain as plain data, for `fit.json`.

        Returns:
            Its knots' elevations and gains.
        """
        return {"knots_deg": self.knots_deg.tolist(), "gain_db": self.gain_db.tolist()}


def elevation_deg(
    scn: Scenario, cell: npt.ArrayLike, x: npt.ArrayLike, y: npt.ArrayLike, z: npt.ArrayLike
) -> np.ndarray:
    """The elevation from points to the antenna of each point's cell, degrees.

    Args:
        scn: The scenario.
        cell: Each point's cell index, or one for all.
        x: East, m.
        y: North, m.
        z: Height above sea level, m.

    Returns:
        Elevations, degrees.
    """
    from rainuav.radio.measured._view import _cells, _site_z

    cells = _cells(scn)
    x, y, z = (np.asarray(v, dtype=float) for v in (x, y, z))
    cell = np.broadcast_to(np.asarray(cell, dtype=np.int64), x.shape)
    out = np.empty(x.shape)
    for c in np.unique(cell):
        m = cell == c
        site = cells[int(c)][0]
        dz = _site_z(scn, site) - z[m]
        out[m] = np.degrees(np.arctan2(dz, np.hypot(x[m] - site.x_m, y[m] - site.y_m)))
    return out


def _basis(knots: np.ndarray, e: np.ndarray) -> np.ndarray:
    e = np.clip(e, knots[0], knots[-1])
    i = np.clip(np.searchsorted(knots, e, side="right") - 1, 0, len(knots) - 2)
    w = (e - knots[i]) / (knots[i + 1] - knots[i])
    b = np.zeros((len(e), len(knots)))
    b[np.arange(len(e)), i] = 1 - w
    b[np.arange(len(e)), i + 1] = w
    return b


def fit_gain(elevation: npt.ArrayLike, resid: npt.ArrayLike) -> ElevationGain:
    """The gain by elevation that best explains the residuals of rows seen at some elevations.

    Args:
        elevation: Each row's elevation to its cell, degrees.
        resid: Each row's residual, dB.

    Returns:
        The [`ElevationGain`][rainuav.radio.measured.pattern.ElevationGain] (the module's docstring
        has the fit).
    """
    e = np.asarray(elevation, dtype=float)
    r = np.asarray(resid, dtype=float)
    lo = np.floor(e.min() / STEP_DEG) * STEP_DEG
    hi = max(np.ceil(e.max() / STEP_DEG) * STEP_DEG, lo + STEP_DEG)
    knots = np.arange(lo, hi + STEP_DEG / 2, STEP_DEG)
    b = _basis(knots, e)
    d = np.diff(np.eye(len(knots)), 2, axis=0)
    a = b.T @ b + SMOOTHING * len(e) * (d.T @ d) + 1e-6 * len(e) * np.eye(len(knots))
    return ElevationGain(knots, np.linalg.solve(a, b.T @ r))


@dataclass(frozen=True)
class HeadingGain:
    """A receive gain by the azimuth of the cell relative to the UAV's nose, dB (module
    docstring): ``cos_db[k]`` and ``sin_db[k]`` the coefficients of order ``k + 1``."""

    cos_db: np.ndarray
    sin_db: np.ndarray

    def at(self, relative_deg: npt.ArrayLike) -> np.ndarray:
        """The gain at azimuths relative to the UAV's nose, dB (0 where the heading is unknown,
        NaN).

        Args:
            relative_deg: Relative azimuths, degrees clockwise.

        Returns:
            The gain, dB.
        """
        phi = np.radians(np.asarray(relative_deg, dtype=float))
        k = np.arange(1, len(self.cos_db) + 1)
        g = np.cos(np.multiply.outer(phi, k)) @ self.cos_db
        g = g + np.sin(np.multiply.outer(phi, k)) @ self.sin_db
        return np.nan_to_num(g)

    @property
    def spread_db(self) -> float:
        """The gain's root mean square over every heading, dB: its spread on a map."""
        return float(np.sqrt(np.sum(self.cos_db**2 + self.sin_db**2) / 2))

    def to_dict(self) -> dict[str, Any]:
        """The gain as plain data, for `fit.json`.

        Returns:
            Its Fourier coefficients (`cos_db`, `sin_db`) and its spread over the heading.
        """
        return {"cos_db": self.cos_db.tolist(), "sin_db": self.sin_db.tolist(),
                "spread_db": self.spread_db}  # fmt: skip


def relative_azimuth_deg(
    scn: Scenario,
    cell: npt.ArrayLike,
    x: npt.ArrayLike,
    y: npt.ArrayLike,
    heading_deg: npt.ArrayLike,
) -> np.ndarray:
    """The azimuth under which the UAV sees each point's cell's site, relative to its nose.

    Args:
        scn: The scenario.
        cell: Each point's cell index, or one for all.
        x: The UAV's east, m.
        y: The UAV's north, m.
        heading_deg: Its heading, degrees clockwise from north.

    Returns:
        Degrees clockwise (NaN where the heading is).
    """
    from rainuav.radio.measured._view import _cells

    cells = _cells(scn)
    x, y = (np.asarray(v, dtype=float) for v in (x, y))
    cell = np.broadcast_to(np.asarray(cell, dtype=np.int64), x.shape)
    bearing = np.empty(x.shape)
    for c in np.unique(cell):
        m = cell == c
        site = cells[int(c)][0]
        bearing[m] = np.degrees(np.arctan2(site.x_m - x[m], site.y_m - y[m]))
    return np.mod(bearing - np.asarray(heading_deg, dtype=float), 360.0)


def fit_heading_gain(relative_deg: npt.ArrayLike, resid: npt.ArrayLike) -> HeadingGain:
    """The heading gain that best explains the residuals of rows seen at relative azimuths.

    Rows of an unknown heading (NaN) are left out; the module's docstring has the fit.

    Args:
        relative_deg: Each row's azimuth to its cell relative to the nose, degrees.
        resid: Each row's residual, dB.

    Returns:
        The [`HeadingGain`][rainuav.radio.measured.pattern.HeadingGain].
    """
    phi = np.radians(np.asarray(relative_deg, dtype=float))
    r = np.asarray(resid, dtype=float)
    ok = np.isfinite(phi) & np.isfinite(r)
    k = np.arange(1, HARMONICS + 1)
    b = np.hstack([np.cos(np.multiply.outer(phi[ok], k)), np.sin(np.multiply.outer(phi[ok], k))])
    a = b.T @ b + 1e-3 * max(int(ok.sum()), 1) * np.eye(2 * HARMONICS)
    coef = np.linalg.solve(a, b.T @ (r[ok] - r[ok].mean()))
    return HeadingGain(coef[:HARMONICS], coef[HARMONICS:])
