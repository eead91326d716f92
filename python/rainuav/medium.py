"""The rain medium: effective permittivity and specific attenuation of rain.

Two models ([physics reference, section 3][3-the-rain-medium]):

- ``"forward-scattering"`` (default): van de Hulst's effective index from each drop's Mie
  forward-scattering amplitude, integrated over the drop-size distribution. Valid across
  1-1000 GHz. Spheroidal drops and polarisation enter through the ratio of the spheroid's
  quasi-static polarisability along the field to the equal-volume sphere's, applied to the
  sphere's Mie amplitude (exact in the Rayleigh limit, an approximation for big drops).
- ``"quasi-static"``: the design paper's dilute Maxwell Garnett mixture with its printed
  typos corrected. Only right while drops are small against the wavelength (below ~3 GHz).

Conventions: time dependence ``exp(+j w t)``, so lossy permittivities have ``Im eps <= 0``;
diameters in mm; N(D) in m^-3 mm^-1; attenuation in dB/km of power.

Frequency and rain rate broadcast against each other like numpy arrays; the other keywords
are scalars. Scalar inputs give Python scalars back. A zero rain rate is clear air
(permittivity exactly 1, attenuation 0).
"""

from __future__ import annotations

from typing import Any, Literal, overload

import numpy as np
import numpy.typing as npt

from rainuav import _core
from rainuav._checks import (
    FloatArray,
    as_real_array,
    as_real_scalar,
    broadcast_flat,
    check_choice,
)
from rainuav._core import DropSizeDistribution

__all__ = [
    "DropSizeDistribution",
    "RainMedium",
    "effective_index",
    "effective_permittivity",
    "gamma_dsd",
    "itu_p838",
    "marshall_palmer",
    "specific_attenuation",
    "tabulated_dsd",
    "water_permittivity",
]

ComplexArray = npt.NDArray[np.complex128]
ArrayLike = Any

MODELS = ("forward-scattering", "quasi-static")
POLARIZATIONS = ("h", "v", "average")
SHAPES = ("sphere", "beard-chuang", "pruppacher-beard")
WIND_MODELS = ("canting", "paper")
#: Named drop-size distributions. Joss et al. (1969) drizzle and thunderstorm spectra are
#: exponential like Marshall-Palmer with other intercepts and slopes.
NAMED_DSDS: dict[str, DropSizeDistribution] = {
    "marshall-palmer": DropSizeDistribution.marshall_palmer(),
    "joss-drizzle": DropSizeDistribution.gamma(30000.0, 0.0, 5.7, -0.21),
    "joss-thunderstorm": DropSizeDistribution.gamma(1400.0, 0.0, 3.0, -0.21),
}

Model = Literal["forward-scattering", "quasi-static"]
Polarization = Literal["h", "v", "average"]
Shape = Literal["sphere", "beard-chuang", "pruppacher-beard"]
WindModel = Literal["canting", "paper"]
DsdLike = str | DropSizeDistribution


def gamma_dsd(
    n0: float, mu: float, lambda_coeff: float, lambda_exp: float, n0_exp: float = 0.0
) -> DropSizeDistribution:
    """A gamma drop-size distribution.

    `N = n0 R^n0_exp D^mu exp(-lambda_coeff R^lambda_exp D)` in m^-3 mm^-1, D in mm, R in mm/h; `mu
    = 0` is exponential, and Marshall-Palmer is `gamma_dsd(8000, 0, 4.1, -0.21)`.

    Args:
        n0: The intercept, m^-3 mm^-1 (times `R^n0_exp`).
        mu: The shape parameter.
        lambda_coeff: The slope's coefficient, mm^-1.
        lambda_exp: The slope's exponent of the rain rate.
        n0_exp: The intercept's exponent of the rain rate.

    Returns:
        A `DropSizeDistribution` for
        [`effective_permittivity()`][rainuav.medium.effective_permittivity]'s `dsd`.
    """
    return DropSizeDistribution.gamma(
        as_real_scalar("n0", n0),
        as_real_scalar("mu", mu),
        as_real_scalar("lambda_coeff", lambda_coeff),
        as_real_scalar("lambda_exp", lambda_exp),
        as_real_scalar("n0_exp", n0_exp),
    )


def tabulated_dsd(diameter_mm: ArrayLike, density: ArrayLike) -> DropSizeDistribution:
    """A measured drop-size distribution, linearly interpolated and zero outside the table.

    The table fixes the spectrum's shape; the concentration scales with rain rate as `R /
    table_rain_rate_mm_h`, the table's own rain rate from Atlas fall speeds, so calling with that
    rate reproduces the table exactly.

    Args:
        diameter_mm: Drop diameters, mm, increasing.
        density: N(D) at each, m^-3 mm^-1.

    Returns:
        A `DropSizeDistribution`.
    """
    d = np.ascontiguousarray(as_real_array("diameter_mm", diameter_mm).ravel())
    n = np.ascontiguousarray(as_real_array("density", density).ravel())
    return DropSizeDistribution.table(d, n)


def _dsd(dsd: DsdLike) -> DropSizeDistribution:
    if isinstance(dsd, DropSizeDistribution):
        return dsd
    name = check_choice("dsd", dsd, tuple(NAMED_DSDS))
    return NAMED_DSDS[name]


def _config(
    model: str,
    polarization: str,
    shape: str,
    temperature_c: float,
    wind_speed_m_s: float,
    dsd: DsdLike,
    wind_model: str,
    nodes_per_panel: int = 16,
) -> _core.MediumConfig:
    return _core.MediumConfig(
        model=check_choice("model", model, MODELS),
        polarization=check_choice("polarization", polarization, POLARIZATIONS),
        shape=check_choice("shape", shape, SHAPES),
        temperature_c=as_real_scalar("temperature_c", temperature_c),
        wind_speed_m_s=as_real_scalar("wind_speed_m_s", wind_speed_m_s),
        wind_model=check_choice("wind_model", wind_model, WIND_MODELS),
        dsd=_dsd(dsd),
        nodes_per_panel=nodes_per_panel,
    )


@overload
def _shaped(values: ComplexArray, shape: tuple[int, ...]) -> complex | ComplexArray: ...
@overload
def _shaped(values: FloatArray, shape: tuple[int, ...]) -> float | FloatArray: ...
def _shaped(values: Any, shape: tuple[int, ...]) -> Any:
    if shape == ():
        return values[0].item()
    return values.reshape(shape)


def water_permittivity(freq_hz: ArrayLike, temperature_c: ArrayLike = 20.0) -> Any:
    """The relative permittivity of liquid water (double Debye, ITU-R P.840; `Im <= 0`).

    Args:
        freq_hz: Frequency, 1e9-1e12 Hz.
        temperature_c: Water temperature, 0-40 C (broadcasts with `freq_hz`).

    Returns:
        The complex permittivity, of the broadcast shape.
    """
    shape, (f, t) = broadcast_flat(freq_hz=freq_hz, temperature_c=temperature_c)
    return _shaped(_core.water_permittivity(f, t), shape)


def marshall_palmer(diameter_mm: ArrayLike, rain_rate_mm_h: ArrayLike) -> Any:
    """Marshall-Palmer's drop-size distribution `N(D) = 8000 exp(-4.1 R^-0.21 D)`.

    Args:
        diameter_mm: Drop diameters, mm.
        rain_rate_mm_h: Rain rate, mm/h (broadcasts with `diameter_mm`; zero for R = 0).

    Returns:
        N(D), m^-3 mm^-1.
    """
    shape, (d, r) = broadcast_flat(diameter_mm=diameter_mm, rain_rate_mm_h=rain_rate_mm_h)
    return _shaped(NAMED_DSDS["marshall-palmer"].density(d, r), shape)


def _medium(
    freq_hz: ArrayLike, rain_rate_mm_h: ArrayLike, config: _core.MediumConfig
) -> tuple[tuple[int, ...], ComplexArray, ComplexArray, FloatArray]:
    shape, (f, r) = broadcast_flat(freq_hz=freq_hz, rain_rate_mm_h=rain_rate_mm_h)
    eps, n, gamma = _core.effective_medium(f, r, config)
    return shape, eps, n, gamma


def effective_permittivity(
    freq_hz: ArrayLike,
    rain_rate_mm_h: ArrayLike,
    *,
    model: Model = "forward-scattering",
    polarization: Polarization = "h",
    shape: Shape = "beard-chuang",
    temperature_c: float = 20.0,
    wind_speed_m_s: float = 0.0,
    dsd: DsdLike = "marshall-palmer",
    wind_model: WindModel = "canting",
) -> Any:
    """Effective relative permittivity of rain (``Im <= 0``).

    Args:
        freq_hz: frequency, 1e9-1e12 Hz.
        rain_rate_mm_h: rain rate, 0-500 mm/h (0 is clear air: exactly 1).
        model: ``"forward-scattering"`` (Mie; default) or ``"quasi-static"`` (the paper's).
        polarization: ``"h"``, ``"v"`` or ``"average"`` (the paper's orientation average).
        shape: ``"sphere"``, ``"beard-chuang"`` or ``"pruppacher-beard"`` (oblate from 1.25 mm).
        temperature_c: water temperature, 0-40 C.
        wind_speed_m_s: horizontal wind across the path, 0-60 m/s.
        dsd: ``"marshall-palmer"``, ``"joss-drizzle"``, ``"joss-thunderstorm"`` or a
            `DropSizeDistribution` from [`gamma_dsd()`][rainuav.medium.gamma_dsd] /
            [`tabulated_dsd()`][rainuav.medium.tabulated_dsd].
        wind_model: ``"canting"`` (drops cant by ``atan(v_wind / v_t)``; default) or
            ``"paper"`` (the paper's ``1/cos(atan(v_wind / v_t))`` factor, unbounded in strong
            wind; for reproducing the paper only).

    Returns:
        The complex permittivity, of the broadcast shape of the frequency and the rain rate.
    """
    cfg = _config(model, polarization, shape, temperature_c, wind_speed_m_s, dsd, wind_model)
    out_shape, eps, _, _ = _medium(freq_hz, rain_rate_mm_h, cfg)
    return _shaped(eps, out_shape)


def effective_index(
    freq_hz: ArrayLike,
    rain_rate_mm_h: ArrayLike,
    *,
    model: Model = "forward-scattering",
    polarization: Polarization = "h",
    shape: Shape = "beard-chuang",
    temperature_c: float = 20.0,
    wind_speed_m_s: float = 0.0,
    dsd: DsdLike = "marshall-palmer",
    wind_model: WindModel = "canting",
) -> Any:
    """The effective refractive index of rain, `n = sqrt(eps)` (`Im n <= 0`).

    Args:
        freq_hz: Frequency, 1e9-1e12 Hz.
        rain_rate_mm_h: Rain rate, 0-500 mm/h.
        model: As [`effective_permittivity()`][rainuav.medium.effective_permittivity]'s.
        polarization: As `effective_permittivity()`'s.
        shape: As `effective_permittivity()`'s.
        temperature_c: As `effective_permittivity()`'s.
        wind_speed_m_s: As `effective_permittivity()`'s.
        dsd: As `effective_permittivity()`'s.
        wind_model: As `effective_permittivity()`'s.

    Returns:
        The complex index, of the broadcast shape of the frequency and the rain rate.
    """
    cfg = _config(model, polarization, shape, temperature_c, wind_speed_m_s, dsd, wind_model)
    out_shape, _, n, _ = _medium(freq_hz, rain_rate_mm_h, cfg)
    return _shaped(n, out_shape)


def specific_attenuation(
    freq_hz: ArrayLike,
    rain_rate_mm_h: ArrayLike,
    *,
    model: Model = "forward-scattering",
    polarization: Polarization = "h",
    shape: Shape = "beard-chuang",
    temperature_c: float = 20.0,
    wind_speed_m_s: float = 0.0,
    dsd: DsdLike = "marshall-palmer",
    wind_model: WindModel = "canting",
) -> Any:
    """The specific attenuation of rain, dB/km of power: `8685.9 k0 |Im n|`.

    Args:
        freq_hz: Frequency, 1e9-1e12 Hz.
        rain_rate_mm_h: Rain rate, 0-500 mm/h.
        model: As [`effective_permittivity()`][rainuav.medium.effective_permittivity]'s.
        polarization: As `effective_permittivity()`'s.
        shape: As `effective_permittivity()`'s.
        temperature_c: As `effective_permittivity()`'s.
        wind_speed_m_s: As `effective_permittivity()`'s.
        dsd: As `effective_permittivity()`'s.
        wind_model: As `effective_permittivity()`'s.

    Returns:
        dB/km, of the broadcast shape of the frequency and the rain rate.
    """
    cfg = _config(model, polarization, shape, temperature_c, wind_speed_m_s, dsd, wind_model)
    out_shape, _, _, gamma = _medium(freq_hz, rain_rate_mm_h, cfg)
    return _shaped(gamma, out_shape)


_TILTS = {"h": 0.0, "v": 90.0, "average": 45.0}


def itu_p838(
    freq_hz: ArrayLike,
    rain_rate_mm_h: ArrayLike,
    *,
    polarization: Polarization = "h",
    elevation_deg: float = 0.0,
    tilt_deg: float | None = None,
) -> Any:
    """ITU-R P.838-3's specific attenuation `k R^alpha`, dB/km.

    Args:
        freq_hz: Frequency, Hz (P.838's 1-1000 GHz).
        rain_rate_mm_h: Rain rate, mm/h.
        polarization: "h" (tilt 0), "v" (tilt 90) or "average" (tilt 45; circular: `k = (kH + kV) /
            2`).
        elevation_deg: The path's elevation, -90 to 90 degrees.
        tilt_deg: Any linear polarisation tilt, degrees; overrides `polarization` when given.

    Returns:
        dB/km, of the broadcast shape of the frequency and the rain rate.
    """
    tilt = _TILTS[check_choice("polarization", polarization, tuple(_TILTS))]
    if tilt_deg is not None:
        tilt = as_real_scalar("tilt_deg", tilt_deg)
    elev = as_real_scalar("elevation_deg", elevation_deg)
    shape, (f, r) = broadcast_flat(freq_hz=freq_hz, rain_rate_mm_h=rain_rate_mm_h)
    return _shaped(_core.itu_p838(f, r, tilt, elev), shape)


class RainMedium:
    """The rain medium at one frequency, for many rain rates.

    Everything that depends only on the frequency and the options (Mie amplitudes on the quadrature
    nodes) is computed once here, so evaluating a map of rain rates is a cheap pass over ~100 nodes
    per value. Keywords as in [`effective_permittivity()`][rainuav.medium.effective_permittivity].
    """

    def __init__(
        self,
        freq_hz: float,
        *,
        model: Model = "forward-scattering",
        polarization: Polarization = "h",
        shape: Shape = "beard-chuang",
        temperature_c: float = 20.0,
        wind_speed_m_s: float = 0.0,
        dsd: DsdLike = "marshall-palmer",
        wind_model: WindModel = "canting",
    ) -> None:
        """Computes the medium's Mie amplitudes on the quadrature nodes, once.

        Args:
            freq_hz: Frequency, 1e9-1e12 Hz.
            model: As [`effective_permittivity()`][rainuav.medium.effective_permittivity]'s.
            polarization: As `effective_permittivity()`'s.
            shape: As `effective_permittivity()`'s.
            temperature_c: As `effective_permittivity()`'s.
            wind_speed_m_s: As `effective_permittivity()`'s.
            dsd: As `effective_permittivity()`'s.
            wind_model: As `effective_permittivity()`'s.
        """
        self.freq_hz = as_real_scalar("freq_hz", freq_hz)
        cfg = _config(model, polarization, shape, temperature_c, wind_speed_m_s, dsd, wind_model)
        self._kernel = _core.RainMediumKernel(self.freq_hz, cfg)

    def _eval(self, rain_rate_mm_h: ArrayLike) -> tuple[Any, Any, Any]:
        r = as_real_array("rain_rate_mm_h", rain_rate_mm_h)
        eps, n, gamma = self._kernel.evaluate(np.ascontiguousarray(r).reshape(-1))
        return _shaped(eps, r.shape), _shaped(n, r.shape), _shaped(gamma, r.shape)

    def permittivity(self, rain_rate_mm_h: ArrayLike) -> Any:
        """The effective relative permittivity at each rain rate.

        Args:
            rain_rate_mm_h: Rain rates, mm/h (any shape).

        Returns:
            The complex permittivity, of the shape of `rain_rate_mm_h`.
        """
        return self._eval(rain_rate_mm_h)[0]

    def refractive_index(self, rain_rate_mm_h: ArrayLike) -> Any:
        """The effective refractive index at each rain rate.

        Args:
            rain_rate_mm_h: Rain rates, mm/h (any shape).

        Returns:
            The complex index, of the shape of `rain_rate_mm_h`.
        """
        return self._eval(rain_rate_mm_h)[1]

    def specific_attenuation(self, rain_rate_mm_h: ArrayLike) -> Any:
        """The specific attenuation at each rain rate, dB/km.

        Args:
            rain_rate_mm_h: Rain rates, mm/h (any shape).

        Returns:
            dB/km, of the shape of `rain_rate_mm_h`.
        """
        return self._eval(rain_rate_mm_h)[2]
