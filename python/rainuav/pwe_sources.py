"""The PE's sources: apertures the march starts from, a Gaussian beam or a tabulated antenna
pattern ([`rainuav.pwe.march()`][rainuav.pwe.march] takes them)."""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from rainuav import _core
from rainuav._checks import as_real_scalar
from rainuav.errors import InvalidInputError

__all__ = ["C0_M_S", "gaussian_beam", "pattern_source"]

C0_M_S = 299_792_458.0

Complex64Array = npt.NDArray[np.complex64]


def _positive(name: str, value: object) -> float:
    v = as_real_scalar(name, value)
    if not (np.isfinite(v) and v > 0):
        raise InvalidInputError(f"{name} must be finite and > 0 (got {value!r})")
    return v


def gaussian_beam(
    nx: int,
    ny: int,
    dx_m: float,
    dy_m: float,
    *,
    freq_hz: float,
    height_m: float,
    elevation_deg: float,
    beamwidth_deg: float,
) -> Complex64Array:
    """A Gaussian-beam aperture, the PE's simplest source.

    Centred at `x = 0` (column nx//2) and `y = height_m`, tilted up by `elevation_deg`, with a
    far-field half-power full width `beamwidth_deg` ([physics reference, section
    4][4-the-split-step-parabolic-equation]):
    `exp(-j k0 sin(el) (y - h)) exp(-a^2 (x^2 + (y - h)^2) / (2 ln 2))`,
    `a = k0 sin(beamwidth / 2)`.

    Args:
        nx: Cross-range points.
        ny: Height points.
        dx_m: Cross-range step, m.
        dy_m: Height step, m.
        freq_hz: Frequency, Hz.
        height_m: The beam's centre height, m.
        elevation_deg: Its tilt up, degrees.
        beamwidth_deg: Its far-field half-power full width, degrees.

    Returns:
        (nx, ny) complex64.
    """
    return _core.gaussian_beam(
        int(nx),
        int(ny),
        _positive("dx_m", dx_m),
        _positive("dy_m", dy_m),
        freq_hz=as_real_scalar("freq_hz", freq_hz),
        height_m=as_real_scalar("height_m", height_m),
        elevation_deg=as_real_scalar("elevation_deg", elevation_deg),
        beamwidth_deg=as_real_scalar("beamwidth_deg", beamwidth_deg),
    )


def pattern_source(
    nx: int,
    ny: int,
    dx_m: float,
    dy_m: float,
    *,
    freq_hz: float,
    height_m: float,
    azimuth_deg: npt.ArrayLike,
    elevation_deg: npt.ArrayLike,
    gain_db: npt.ArrayLike,
    tilt_deg: float = 0.0,
) -> Complex64Array:
    """An aperture synthesised from a tabulated antenna power pattern.

    The aperture's angular spectrum is the amplitude pattern `10^(gain_db / 20)` sampled at
    `sin(angle) = k / k0` (bilinear, zero outside the table and for evanescent waves), shifted to
    `height_m` and brought to the aperture plane by an inverse FFT; `x = (ix - nx//2) dx`, `y = iy
    dy`, as [`gaussian_beam()`][rainuav.pwe.gaussian_beam].

    Args:
        nx: Cross-range points.
        ny: Height points.
        dx_m: Cross-range step, m.
        dy_m: Height step, m.
        freq_hz: Frequency, Hz.
        height_m: The antenna's height, m.
        azimuth_deg: The table's cross-range angles, degrees, increasing.
        elevation_deg: Its elevations, degrees, increasing.
        gain_db: `gain_db[i, j]` at `(azimuth_deg[i], elevation_deg[j])`, relative to boresight.
        tilt_deg: Boresight's tilt up, degrees.

    Returns:
        (nx, ny) complex64.

    Raises:
        InvalidInputError: Angles that do not increase, a table of another shape or not finite, or a
            pattern with no energy inside the propagating spectrum.
    """
    az = np.asarray(azimuth_deg, dtype=np.float64)
    el = np.asarray(elevation_deg, dtype=np.float64)
    g = np.asarray(gain_db, dtype=np.float64)
    if az.ndim != 1 or el.ndim != 1 or g.shape != (az.size, el.size):
        raise InvalidInputError(
            "gain_db must have shape (len(azimuth_deg), len(elevation_deg)) "
            f"(got {g.shape} for {az.shape}, {el.shape})"
        )
    if az.size < 2 or el.size < 2 or np.any(np.diff(az) <= 0) or np.any(np.diff(el) <= 0):
        raise InvalidInputError("azimuth_deg and elevation_deg must increase, >= 2 values each")
    if not (np.all(np.isfinite(g)) and np.all(np.isfinite(az)) and np.all(np.isfinite(el))):
        raise InvalidInputError("the pattern table must be finite")
    dx, dy = _positive("dx_m", dx_m), _positive("dy_m", dy_m)
    freq = _positive("freq_hz", freq_hz)
    h = as_real_scalar("height_m", height_m)
    tilt = as_real_scalar("tilt_deg", tilt_deg)
    _core.check_memory(int(6 * nx * ny * 16))
    k0 = 2 * np.pi * freq / C0_M_S
    kx = 2 * np.pi * np.fft.fftfreq(nx, dx)
    ky = 2 * np.pi * np.fft.fftfreq(ny, dy)
    sx = np.clip(kx / k0, -1.0, 1.0)
    sy = np.clip(ky / k0, -1.0, 1.0)
    ang_x = np.degrees(np.arcsin(sx))
    ang_y = np.degrees(np.arcsin(sy)) - tilt
    amp = 10.0 ** (g / 20.0)
    # Bilinear interpolation of the amplitude pattern, zero outside the table.
    ix = np.interp(ang_x, az, np.arange(az.size), left=-1, right=-1)
    iy = np.interp(ang_y, el, np.arange(el.size), left=-1, right=-1)
    spec = np.zeros((nx, ny))
    okx, oky = ix >= 0, iy >= 0
    x0 = np.clip(np.floor(ix).astype(int), 0, az.size - 2)
    y0 = np.clip(np.floor(iy).astype(int), 0, el.size - 2)
    tx, ty = ix - x0, iy - y0
    a = amp[x0][:, y0]
    b = amp[x0 + 1][:, y0]
    c = amp[x0][:, y0 + 1]
    d = amp[x0 + 1][:, y0 + 1]
    interp = (
        a * np.outer(1 - tx, 1 - ty)
        + b * np.outer(tx, 1 - ty)
        + c * np.outer(1 - tx, ty)
        + d * np.outer(tx, ty)
    )
    spec[np.ix_(okx, oky)] = interp[np.ix_(okx, oky)]
    propagating = (kx[:, None] ** 2 + ky[None, :] ** 2) < k0**2
    spec = spec * propagating
    # A wave leaving at positive angles is exp(-j k0 sin(angle) y) (docs/physics.md convention),
    # which numpy's inverse FFT holds at negative wavenumbers: mirror the sampled pattern.
    spec = spec[(-np.arange(nx)) % nx][:, (-np.arange(ny)) % ny]
    # Centre the aperture at x = 0 (column nx//2) and y = h: f(r - r0) <-> F(k) exp(-j k r0).
    shift = np.exp(-1j * kx[:, None] * (nx // 2) * dx) * np.exp(-1j * ky[None, :] * h)
    u = np.fft.ifft2(spec * shift)
    peak = np.abs(u).max()
    if peak == 0:
        raise InvalidInputError("the pattern has no energy inside the propagating spectrum")
    return np.ascontiguousarray((u / peak).astype(np.complex64))
