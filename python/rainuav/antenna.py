"""Antenna gain patterns: gain in dBi at (azimuth, elevation) in the antenna's own frame.

Conventions ([physics reference, section 7][7-antennas]): azimuth from the antenna's boresight
azimuth, counter-clockwise (toward +y when the boresight is +x), degrees, wrapped to [-180, 180);
elevation positive up, degrees. Every pattern is vectorised (numpy broadcasting over the two angle
arrays) and returns float64 dBi.

- [`tr38901_element()`][rainuav.antenna.tr38901_element]: the 3GPP TR 38.901 sector element (Table
  7.3-1: 65 degree half-power widths, SLA_V 30 dB, A_max 30 dB, 8 dBi).
- [`uniform_array()`][rainuav.antenna.uniform_array]: a uniform vertical array of that element
  (rows, spacing in wavelengths, electrical tilt by phase progression), optionally with columns;
  gain = element + array factor, normalised so that the pattern integrates to 4 pi over the sphere.
- [`gaussian()`][rainuav.antenna.gaussian]: the paper's beam ([physics reference, section
  4][4-the-split-step-parabolic-equation]), optionally
  with a sidelobe floor (then normalised to 4 pi as well: a floor adds power in every direction).
- [`tabulated()`][rainuav.antenna.tabulated]: a measured or computed table, bilinear in (azimuth,
  elevation).

[`sphere_mean()`][rainuav.antenna.sphere_mean] is the mean linear gain over the sphere (1 for a
lossless pattern)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Protocol

import numpy as np
import numpy.typing as npt

from rainuav._checks import as_real_array
from rainuav._checks import check_number as _num
from rainuav.errors import InvalidInputError

__all__ = [
    "GaussianBeam",
    "Pattern",
    "TR38901Element",
    "TabulatedPattern",
    "UniformArray",
    "gaussian",
    "sphere_mean",
    "tabulated",
    "tr38901_element",
    "uniform_array",
]

FloatArray = npt.NDArray[np.float64]
_LN2 = math.log(2.0)
_FLOOR_LINEAR = 1e-20
"""Linear gain below which an array-factor null is held (-200 dB), so logs stay finite."""


class Pattern(Protocol):
    """Anything with a vectorised ``gain_dbi(azimuth_deg, elevation_deg)``."""

    def gain_dbi(self, azimuth_deg: npt.ArrayLike, elevation_deg: npt.ArrayLike) -> FloatArray:
        """The gain toward directions, dBi.

        Args:
            azimuth_deg: Azimuths from the boresight, degrees.
            elevation_deg: Elevations, degrees (broadcasts with `azimuth_deg`).

        Returns:
            The gain, dBi, of the broadcast shape.
        """
        ...


def _angles(
    azimuth_deg: npt.ArrayLike, elevation_deg: npt.ArrayLike
) -> tuple[FloatArray, FloatArray]:
    az = as_real_array("azimuth_deg", azimuth_deg)
    el = as_real_array("elevation_deg", elevation_deg)
    if not (np.all(np.isfinite(az)) and np.all(np.isfinite(el))):
        raise InvalidInputError("azimuth_deg and elevation_deg must be finite")
    if np.any(np.abs(el) > 90.0):
        raise InvalidInputError("elevation_deg must be within -90..90 degrees")
    try:
        az, el = np.broadcast_arrays(az, el)
    except ValueError as err:
        raise InvalidInputError(
            f"azimuth_deg {az.shape} and elevation_deg {el.shape} do not broadcast"
        ) from err
    return (az + 180.0) % 360.0 - 180.0, el


def sphere_mean(pattern: Pattern, n: int = 720) -> float:
    """The mean linear gain of a pattern over the sphere, `(1 / 4 pi) integral G dOmega`.

    Gauss-Legendre in `sin(elevation)` (`n` nodes) times the periodic trapezoid rule in azimuth (`2
    n` nodes): exact for smooth patterns to far below 1e-3 at the default.

    Args:
        pattern: The pattern.
        n: Nodes in elevation.

    Returns:
        The mean gain (1 for an isotropic or lossless normalised pattern).
    """
    u, w = np.polynomial.legendre.leggauss(n)
    el = np.degrees(np.arcsin(u))
    az = -180.0 + 360.0 * (np.arange(2 * n) + 0.5) / (2 * n)
    g = 10.0 ** (pattern.gain_dbi(az[None, :], el[:, None]) / 10.0)
    # dOmega = d(sin el) d(az): weights w in sin(el), 2 pi / (2 n) in azimuth.
    return float((w[:, None] * g).sum() * (2 * math.pi / (2 * n)) / (4 * math.pi))


# -- 3GPP TR 38.901 element ---------------------------------------------------------------------
@dataclass(frozen=True)
class TR38901Element:
    """The TR 38.901 Table 7.3-1 element:
    ``A_V = -min(12 ((th - 90) / hpbw_v)^2, sla_v)``, ``A_H = -min(12 (ph / hpbw_h)^2, a_max)``,
    ``A = -min(-(A_V + A_H), a_max)``, gain ``g_max + A`` (th = 90 - elevation)."""

    g_max_dbi: float = 8.0
    hpbw_h_deg: float = 65.0
    hpbw_v_deg: float = 65.0
    sla_v_db: float = 30.0
    a_max_db: float = 30.0

    def __post_init__(self) -> None:
        _num("g_max_dbi", self.g_max_dbi, -50.0, 60.0, " dBi")
        _num("hpbw_h_deg", self.hpbw_h_deg, 1.0, 360.0, " degrees")
        _num("hpbw_v_deg", self.hpbw_v_deg, 1.0, 180.0, " degrees")
        _num("sla_v_db", self.sla_v_db, 0.0, 100.0, " dB")
        _num("a_max_db", self.a_max_db, 0.0, 100.0, " dB")

    def gain_dbi(self, azimuth_deg: npt.ArrayLike, elevation_deg: npt.ArrayLike) -> FloatArray:
        """The element's gain toward directions, dBi (TR 38.901 Table 7.3-1).

        Args:
            azimuth_deg: Azimuths from the boresight, degrees.
            elevation_deg: Elevations, degrees (broadcasts with `azimuth_deg`).

        Returns:
            The gain, dBi, of the broadcast shape.
        """
        ph, el = _angles(azimuth_deg, elevation_deg)
        a_v = -np.minimum(12.0 * (el / self.hpbw_v_deg) ** 2, self.sla_v_db)
        a_h = -np.minimum(12.0 * (ph / self.hpbw_h_deg) ** 2, self.a_max_db)
        return self.g_max_dbi - np.minimum(-(a_v + a_h), self.a_max_db)


def tr38901_element(**overrides: float) -> TR38901Element:
    """The TR 38.901 sector element (65 degree widths, SLA_V 30 dB, A_max 30 dB, 8 dBi).

    Args:
        **overrides: Parameters to change, by name (`g_max_dbi`, `hpbw_h_deg`, `hpbw_v_deg`,
            `sla_v_db`, `a_max_db`).

    Returns:
        The [`TR38901Element`][rainuav.antenna.TR38901Element].
    """
    return TR38901Element(**overrides)


# -- uniform arrays -------------------------------------------------------------------------
def _array_factor(n: int, psi: FloatArray) -> FloatArray:
    """``|sum_k exp(j k psi)|^2 / n`` for k < n (peak n at psi = 0 mod 2 pi), summed term by
    term into one array (no (..., n) temporary)."""
    step = np.exp(1j * psi)
    term = np.ones_like(step)
    s = np.zeros_like(step)
    for _ in range(n):
        s += term
        term *= step
    return np.abs(s) ** 2 / n


@dataclass(frozen=True)
class UniformArray:
    """A planar array of identical elements: ``rows`` in a vertical column ``spacing`` wavelengths
    apart, steered by phase progression to elevation ``electrical_tilt_deg`` (positive up: a 10
    degree downtilt is -10), and ``columns`` side by side ``column_spacing`` wavelengths apart
    (broadside). Gain in dBi: ``element + 10 log10(|AF_v|^2 |AF_h|^2) + norm_db`` with ``|AF_v|^2 =
    |sum_n exp(j 2 pi n d (sin e - sin e0))|^2 / rows`` ([physics reference, section 7][7-antennas])
    and ``|AF_h|^2 = |sum_m exp(j 2 pi m d_h cos e sin ph)|^2 / columns``; ``norm_db`` makes the
    pattern integrate to 4 pi over the sphere."""

    element: TR38901Element = field(default_factory=TR38901Element)
    rows: int = 8
    spacing: float = 0.5
    electrical_tilt_deg: float = -10.0
    columns: int = 1
    column_spacing: float = 0.5
    norm_db: float = field(init=False, default=0.0)

    def __post_init__(self) -> None:
        for name, lo in (("rows", 1), ("columns", 1)):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or not lo <= v <= 64:
                raise InvalidInputError(f"{name} must be an integer within 1..64 (got {v!r})")
        _num("spacing", self.spacing, 0.05, 4.0, " wavelengths")
        _num("column_spacing", self.column_spacing, 0.05, 4.0, " wavelengths")
        _num("electrical_tilt_deg", self.electrical_tilt_deg, -90.0, 90.0, " degrees")
        object.__setattr__(self, "norm_db", -10.0 * math.log10(sphere_mean(self)))

    def array_gain_db(self, azimuth_deg: npt.ArrayLike, elevation_deg: npt.ArrayLike) -> FloatArray:
        """The array factor's gain, `10 log10(|AF_v|^2 |AF_h|^2)` (peak `10 log10(rows x columns)`).

        Args:
            azimuth_deg: Azimuths from the boresight, degrees.
            elevation_deg: Elevations, degrees (broadcasts with `azimuth_deg`).

        Returns:
            dB, of the broadcast shape.
        """
        ph, el = _angles(azimuth_deg, elevation_deg)
        e, p = np.radians(el), np.radians(ph)
        sin_e0 = math.sin(math.radians(self.electrical_tilt_deg))
        psi_v = 2 * math.pi * self.spacing * (np.sin(e) - sin_e0)
        af = _array_factor(self.rows, psi_v)
        if self.columns > 1:
            psi_h = 2 * math.pi * self.column_spacing * np.cos(e) * np.sin(p)
            af = af * _array_factor(self.columns, psi_h)
        return 10.0 * np.log10(np.maximum(af, _FLOOR_LINEAR))

    def gain_dbi(self, azimuth_deg: npt.ArrayLike, elevation_deg: npt.ArrayLike) -> FloatArray:
        """The array's gain toward directions, dBi: the element's and the array factor's.

        Args:
            azimuth_deg: Azimuths from the boresight, degrees.
            elevation_deg: Elevations, degrees (broadcasts with `azimuth_deg`).

        Returns:
            The gain, dBi, of the broadcast shape.
        """
        return (
            self.element.gain_dbi(azimuth_deg, elevation_deg)
            + self.array_gain_db(azimuth_deg, elevation_deg)
            + self.norm_db
        )


def uniform_array(
    rows: int = 8,
    spacing: float = 0.5,
    electrical_tilt_deg: float = -10.0,
    *,
    columns: int = 1,
    column_spacing: float = 0.5,
    element: TR38901Element | None = None,
) -> UniformArray:
    """A uniform array of TR 38.901 elements.

    Args:
        rows: Elements in a column.
        spacing: The rows' spacing, wavelengths.
        electrical_tilt_deg: The beam's steering in elevation, degrees (negative: down).
        columns: Columns of elements.
        column_spacing: The columns' spacing, wavelengths.
        element: The element; None: TR 38.901's default.

    Returns:
        The [`UniformArray`][rainuav.antenna.UniformArray].
    """
    return UniformArray(
        element=element or TR38901Element(),
        rows=rows,
        spacing=spacing,
        electrical_tilt_deg=electrical_tilt_deg,
        columns=columns,
        column_spacing=column_spacing,
    )


# -- the paper's Gaussian beam ----------------------------------------------------------------
@dataclass(frozen=True)
class GaussianBeam:
    """The paper's beam in the far field ([physics reference, sections
    4][4-the-split-step-parabolic-equation] and [7][7-antennas]): ``G = G0 exp(-4 ln2 (ph / bw_h)^2)
    exp(-4 ln2 ((e - tilt) / bw_v)^2)`` with ``G0 = 4 ln2 / (sin(bw_h / 2) sin(bw_v / 2))`` (the PE
    source's directivity). With ``floor_db`` the gain never falls below ``G0 - floor_db`` (a
    stand-in for sidelobes and back lobes), and the whole pattern is scaled so it integrates to 4 pi
    (``norm_db``, the power the floor takes from the main beam)."""

    beamwidth_h_deg: float = 4.333
    beamwidth_v_deg: float = 4.333
    tilt_deg: float = 5.0
    floor_db: float | None = None
    norm_db: float = field(init=False, default=0.0)

    def __post_init__(self) -> None:
        _num("beamwidth_h_deg", self.beamwidth_h_deg, 0.5, 120.0, " degrees")
        _num("beamwidth_v_deg", self.beamwidth_v_deg, 0.5, 120.0, " degrees")
        _num("tilt_deg", self.tilt_deg, -90.0, 90.0, " degrees")
        if self.floor_db is not None:
            _num("floor_db", self.floor_db, 0.0, 200.0, " dB below the peak")
            object.__setattr__(self, "norm_db", -10.0 * math.log10(sphere_mean(self)))

    @property
    def peak_dbi(self) -> float:
        """``G0`` in dBi (before ``norm_db``)."""
        sh = math.sin(math.radians(self.beamwidth_h_deg) / 2)
        sv = math.sin(math.radians(self.beamwidth_v_deg) / 2)
        return 10.0 * math.log10(4 * _LN2 / (sh * sv))

    def gain_dbi(self, azimuth_deg: npt.ArrayLike, elevation_deg: npt.ArrayLike) -> FloatArray:
        """The beam's gain toward directions, dBi.

        Args:
            azimuth_deg: Azimuths from the boresight, degrees.
            elevation_deg: Elevations, degrees (broadcasts with `azimuth_deg`).

        Returns:
            The gain, dBi, of the broadcast shape.
        """
        ph, el = _angles(azimuth_deg, elevation_deg)
        # Exponent in dB: 10 log10(exp(-4 ln2 x^2)) = -(40 ln2 / ln10) x^2 = -12.04 x^2.
        k = 40.0 * _LN2 / math.log(10.0)
        x_h = ph / self.beamwidth_h_deg
        x_v = (el - self.tilt_deg) / self.beamwidth_v_deg
        rel = -k * (x_h**2 + x_v**2)
        if self.floor_db is not None:
            rel = np.maximum(rel, -self.floor_db)
        return self.peak_dbi + rel + self.norm_db


def gaussian(
    beamwidth_deg: float = 4.333,
    *,
    beamwidth_v_deg: float | None = None,
    tilt_deg: float = 5.0,
    floor_db: float | None = None,
) -> GaussianBeam:
    """The paper's Gaussian beam.

    Args:
        beamwidth_deg: The beam's width, degrees.
        beamwidth_v_deg: The width in elevation, degrees; None: `beamwidth_deg`.
        tilt_deg: The boresight's elevation, degrees (positive: up).
        floor_db: A floor this far below the peak, dB; None: the pure beam.

    Returns:
        The [`GaussianBeam`][rainuav.antenna.GaussianBeam].
    """
    bv = beamwidth_deg if beamwidth_v_deg is None else beamwidth_v_deg
    return GaussianBeam(beamwidth_deg, bv, tilt_deg, floor_db)


# -- tables ---------------------------------------------------------------------------------
@dataclass(frozen=True)
class TabulatedPattern:
    """Gain on an (azimuth, elevation) grid, bilinear between nodes; directions outside the
    table get its lowest gain. With ``normalise`` the table is taken as relative gain and
    shifted so the pattern integrates to 4 pi (``norm_db``); without, as dBi."""

    azimuth_deg: tuple[float, ...]
    elevation_deg: tuple[float, ...]
    gain_db: tuple[tuple[float, ...], ...]
    normalise: bool = True
    norm_db: float = field(init=False, default=0.0)
    _table: tuple[FloatArray, FloatArray, FloatArray] = field(
        init=False,
        repr=False,
        compare=False,
        default=None,  # type: ignore[assignment]
    )

    def __post_init__(self) -> None:
        az = as_real_array("azimuth_deg", self.azimuth_deg)
        el = as_real_array("elevation_deg", self.elevation_deg)
        g = as_real_array("gain_db", self.gain_db)
        axes = (("azimuth_deg", az, -180.0, 180.0), ("elevation_deg", el, -90.0, 90.0))
        for name, axis, lo, hi in axes:
            if axis.ndim != 1 or axis.size < 2 or not np.all(np.isfinite(axis)):
                raise InvalidInputError(f"{name} must hold at least two finite angles")
            if not (np.all(np.diff(axis) > 0) and axis[0] >= lo and axis[-1] <= hi):
                raise InvalidInputError(f"{name} must increase strictly within {lo:g}..{hi:g}")
        if g.shape != (az.size, el.size):
            raise InvalidInputError(
                f"gain_db must have shape (len(azimuth_deg), len(elevation_deg)) = "
                f"{(az.size, el.size)} (got {g.shape})"
            )
        if not np.all(np.isfinite(g)):
            raise InvalidInputError("gain_db must be finite everywhere (no NaN or inf)")
        object.__setattr__(self, "_table", (az, el, g))  # the arrays, converted once
        if self.normalise:
            object.__setattr__(self, "norm_db", -10.0 * math.log10(sphere_mean(self)))

    def gain_dbi(self, azimuth_deg: npt.ArrayLike, elevation_deg: npt.ArrayLike) -> FloatArray:
        """The table's gain toward directions, dBi: bilinear between nodes, its lowest gain outside.

        Args:
            azimuth_deg: Azimuths from the boresight, degrees.
            elevation_deg: Elevations, degrees (broadcasts with `azimuth_deg`).

        Returns:
            The gain, dBi, of the broadcast shape.
        """
        ph, el = _angles(azimuth_deg, elevation_deg)
        az, ev, g = self._table
        inside = (ph >= az[0]) & (ph <= az[-1]) & (el >= ev[0]) & (el <= ev[-1])
        i = np.clip(np.searchsorted(az, ph, side="right") - 1, 0, az.size - 2)
        j = np.clip(np.searchsorted(ev, el, side="right") - 1, 0, ev.size - 2)
        ti = np.clip((ph - az[i]) / (az[i + 1] - az[i]), 0.0, 1.0)
        tj = np.clip((el - ev[j]) / (ev[j + 1] - ev[j]), 0.0, 1.0)
        v = (
            g[i, j] * (1 - ti) * (1 - tj)
            + g[i + 1, j] * ti * (1 - tj)
            + g[i, j + 1] * (1 - ti) * tj
            + g[i + 1, j + 1] * ti * tj
        )
        return np.where(inside, v, g.min()) + self.norm_db


def tabulated(
    azimuth_deg: npt.ArrayLike,
    elevation_deg: npt.ArrayLike,
    gain_db: npt.ArrayLike,
    *,
    normalise: bool = True,
) -> TabulatedPattern:
    """A pattern from a table of gains.

    Args:
        azimuth_deg: The table's azimuths, degrees.
        elevation_deg: The table's elevations, degrees.
        gain_db: `gain_db[i][j]` at `(azimuth_deg[i], elevation_deg[j])` (the form of
            [`Pattern`][rainuav.radio.scene.cell.Pattern]).
        normalise: Take the table as relative gain, shifted so the pattern integrates to 4 pi;
            False: as dBi.

    Returns:
        The [`TabulatedPattern`][rainuav.antenna.TabulatedPattern].

    Raises:
        InvalidInputError: A table that is not 2-D or not finite, axes that do not increase strictly
            within their ranges, or axes that do not match the table.
    """

    g = as_real_array("gain_db", gain_db)
    if g.ndim != 2:
        raise InvalidInputError(f"gain_db must be a 2-D table (got shape {g.shape})")
    return TabulatedPattern(
        tuple(float(x) for x in as_real_array("azimuth_deg", azimuth_deg).ravel()),
        tuple(float(x) for x in as_real_array("elevation_deg", elevation_deg).ravel()),
        tuple(tuple(float(x) for x in row) for row in g),
        normalise,
    )
