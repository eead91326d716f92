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
    """Gamma drop-size distribution ``N = n0 R^n0_exp D^mu exp(-lambda_coeff R^lambda_exp D)``
    (m^-3 mm^-1, D in mm, R in mm/h). ``mu = 0`` is exponential; Marshall-Palmer is
    ``gamma_dsd(8000, 0, 4.1, -0.21)``."""
    return DropSizeDistribution.gamma(
        as_real_scalar("n0", n0),
        as_real_scalar("mu", mu),
        as_real_scalar("lambda_coeff", lambda_coeff),
        as_real_scalar("lambda_exp", lambda_exp),
        as_real_scalar("n0_exp", n0_exp),
    )


def tabulated_dsd(diameter_mm: ArrayLike, density: ArrayLike) -> DropSizeDistribution:
    """A measured N(D) (m^-3 mm^-1 at increasing ``diameter_mm``), linearly interpolated and
    zero outside the table. The table fixes the spectrum's shape; the concentration scales
    with rain rate as ``R / table_rain_rate_mm_h``, the table's own rain rate from Atlas fall
    speeds, so calling with that rate reproduces the table exactly."""
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
    """Relative permittivity of liquid water (double Debye, ITU-R P.840; ``Im <= 0``).

    ``freq_hz`` within 1e9-1e12, ``temperature_c`` within 0-40; they broadcast."""
    shape, (f, t) = broadcast_flat(freq_hz=freq_hz, temperature_c=temperature_c)
    return _shaped(_core.water_permittivity(f, t), shape)


def marshall_palmer(diameter_mm: ArrayLike, rain_rate_mm_h: ArrayLike) -> Any:
    """Marshall-Palmer ``N(D) = 8000 exp(-4.1 R^-0.21 D)`` in m^-3 mm^-1 (zero for R = 0)."""
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
    """Effective refractive index ``n = sqrt(eps)`` of rain (``Im n <= 0``); the keywords
    are those of [`effective_permittivity()`][rainuav.medium.effective_permittivity]."""
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
    """Specific attenuation of rain in dB/km (power): ``8685.9 k0 |Im n|``. The keywords are
    those of [`effective_permittivity()`][rainuav.medium.effective_permittivity]."""
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
    """ITU-R P.838-3 specific attenuation ``k R^alpha`` in dB/km.

    ``polarization`` ``"h"`` is tilt 0, ``"v"`` tilt 90 and ``"average"`` tilt 45 (circular:
    ``k = (kH + kV)/2``). ``tilt_deg``, when given, sets any linear tilt and overrides
    ``polarization``. ``elevation_deg`` is the path elevation (-90 to 90)."""
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
        self.freq_hz = as_real_scalar("freq_hz", freq_hz)
        cfg = _config(model, polarization, shape, temperature_c, wind_speed_m_s, dsd, wind_model)
        self._kernel = _core.RainMediumKernel(self.freq_hz, cfg)

    def _eval(self, rain_rate_mm_h: ArrayLike) -> tuple[Any, Any, Any]:
        r = as_real_array("rain_rate_mm_h", rain_rate_mm_h)
        eps, n, gamma = self._kernel.evaluate(np.ascontiguousarray(r).reshape(-1))
        return _shaped(eps, r.shape), _shaped(n, r.shape), _shaped(gamma, r.shape)

    def permittivity(self, rain_rate_mm_h: ArrayLike) -> Any:
        """Effective relative permittivity at each rain rate."""
        return self._eval(rain_rate_mm_h)[0]

    def refractive_index(self, rain_rate_mm_h: ArrayLike) -> Any:
        """Effective refractive index at each rain rate."""
        return self._eval(rain_rate_mm_h)[1]

    def specific_attenuation(self, rain_rate_mm_h: ArrayLike) -> Any:
        """Specific attenuation in dB/km at each rain rate."""
        return self._eval(rain_rate_mm_h)[2]
