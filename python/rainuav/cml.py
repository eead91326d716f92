"""Rain attenuation measured by real commercial microwave links against the rain medium
([`rainuav.medium`][rainuav.medium]) and ITU-R P.838-3 (the ``itur`` package): the validation page
"Rain against real links".

The data are pycomlink's example (shipped in its wheel; ``pycomlink`` is in the ``test`` extra):
500 links of a German network over ten days of May 2018, one-minute transmitted and received
levels of both channels, each channel's frequency (6.5-38.9 GHz) and polarisation, each link's
length, and the path-averaged rain of the RADOLAN-RW radar product along each link, five-minute
sums.

The measured rain attenuation is made with pycomlink's own processing, as its tutorial does it:
total loss ``tsl - rsl`` (gaps up to five minutes interpolated), wet where the rolling standard
deviation of the loss over 60 minutes exceeds 0.8 dB, a constant baseline (the mean of the last
five dry minutes, ``baseline_constant``), the wet-antenna attenuation of Leijnse et al. (2008,
``waa_leijnse_2008_from_A_obs``, its default antenna film), the rest clipped at 0. It is averaged
over the radar's five minutes.

The predictions: the specific attenuation at the radar's mean rain rate over each five minutes,
times the link's length, from rainuav's medium (forward scattering, Marshall-Palmer drops,
Beard-Chuang shapes, 20 C: the package's defaults) and from ITU-R P.838-3, each at the channel's
frequency and polarisation. Compared where the radar sees rain (more than
[`WET_RAIN_MM_H`][rainuav.cml.WET_RAIN_MM_H] on the link): bias (predicted minus measured), RMSE
and Pearson's correlation, by frequency band and polarisation. None of these choices was tuned:
the processing is the tutorial's, the medium the package's defaults.
"""

from __future__ import annotations

import os
from typing import Any

import numpy as np

__all__ = [
    "BANDS_GHZ",
    "WET_RAIN_MM_H",
    "compare",
    "measured_attenuation",
    "predictions",
    "stats",
]

BANDS_GHZ = ((6.0, 15.0), (15.0, 25.0), (25.0, 40.0))
"""The frequency bands the statistics are given for, GHz (lower bound inclusive)."""
WET_RAIN_MM_H = 0.1
"""Five-minute intervals compared: the radar's path-averaged rain above this, mm/h."""


def load(links: int) -> tuple[Any, Any]:
    """The links' one-minute levels and their radar rain (pycomlink's example data).

    Args:
        links: How many links, from the first.

    Returns:
        `(cmls, radar)`: the links' dataset and the radar rain along them.
    """
    import pycomlink.io.examples as examples
    import xarray as xr

    path = examples.get_example_data_path()
    cmls = xr.open_dataset(os.path.join(path, "example_cml_data.nc")).isel(cml_id=slice(0, links))
    radar = xr.open_dataset(os.path.join(path, "example_path_averaged_reference_data.nc"))
    return cmls.load(), radar.rainfall_amount.isel(cml_id=slice(0, links)).load()


def measured_attenuation(cmls: Any) -> Any:
    """Each channel's rain attenuation every minute, by pycomlink's processing.

    Args:
        cmls: The links' dataset.

    Returns:
        The attenuation, dB.
    """
    import pycomlink as pycml

    tl = (cmls.tsl - cmls.rsl).interpolate_na(dim="time", method="linear", max_gap="5min")
    wet = tl.rolling(time=60, center=True).std(skipna=False) > 0.8
    baseline = pycml.processing.baseline.baseline_constant(trsl=tl, wet=wet, n_average_last_dry=5)
    a_obs = (tl - baseline).clip(min=0)
    waa = pycml.processing.wet_antenna.waa_leijnse_2008_from_A_obs(
        A_obs=a_obs, f_Hz=cmls.frequency, pol=cmls.polarization, L_km=cmls.length
    )
    return (tl - baseline - waa).clip(min=0)


def predictions(
    freq_hz: np.ndarray, pol: np.ndarray, length_km: np.ndarray, rain_mm_h: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """The predicted attenuation from rainuav's medium and from ITU-R P.838-3 (`itur`).

    Args:
        freq_hz: Each link's frequency, Hz.
        pol: Each link's polarisation ("h" or "v").
        length_km: Each link's length, km.
        rain_mm_h: The radar's rain along each link, mm/h.

    Returns:
        `(rainuav's, P.838's)` attenuation, dB.
    """
    import itur

    from rainuav import medium

    ours = np.zeros_like(rain_mm_h)
    p838 = np.zeros_like(rain_mm_h)
    for f in np.unique(freq_hz):
        for p in ("h", "v"):
            sel = (freq_hz == f) & (pol == p)
            if not sel.any():
                continue
            r = rain_mm_h[sel]
            ours[sel] = medium.specific_attenuation(f, r, polarization=p) * length_km[sel]
            tau = 0.0 if p == "h" else 90.0
            g = itur.models.itu838.rain_specific_attenuation(r, f / 1e9, 0.0, tau)
            p838[sel] = np.asarray(g.value, dtype=float) * length_km[sel]
    return ours, p838


def stats(pred: np.ndarray, meas: np.ndarray) -> dict[str, float]:
    """Bias (mean of predicted minus measured), RMSE and Pearson's correlation, dB.

    Args:
        pred: The predictions, dB.
        meas: The measurements, dB.

    Returns:
        `n` (the pairs), `bias_db`, `rmse_db` and `r`.
    """
    e = pred - meas
    r = float(np.corrcoef(pred, meas)[0, 1]) if pred.size > 2 else float("nan")
    return {"n": int(pred.size), "bias_db": float(e.mean()),
            "rmse_db": float(np.sqrt((e**2).mean())), "r": r}  # fmt: skip


def compare(links: int = 500) -> dict[str, Any]:
    """The medium against real links: the counts, a row a band and polarisation, and all together.

    Args:
        links: How many links, from the first (the module's docstring has the processing).

    Returns:
        The counts, `groups` (a row a band and polarisation), `all`, and `_arrays` (measured,
        rainuav's, P.838's, frequency, the link's index).
    """
    cmls, radar = load(links)
    a = measured_attenuation(cmls)
    a5 = a.resample(time="5min", label="right", closed="right").mean()
    rain = (radar * 12.0).transpose("cml_id", "time")  # mm in 5 min -> mm/h
    a5 = a5.reindex(time=rain.time).transpose("channel_id", "cml_id", "time")
    n_ch = a5.sizes["channel_id"]
    by_channel = ("channel_id", "cml_id")
    freq = np.broadcast_to(cmls.frequency.transpose(*by_channel).values[..., None], a5.shape)
    pol = np.char.lower(cmls.polarization.transpose(*by_channel).values.astype(str))
    pol = np.broadcast_to(pol[..., None], a5.shape)
    length = np.broadcast_to(cmls.length.values[None, :, None], a5.shape)
    link = np.broadcast_to(np.arange(a5.sizes["cml_id"])[None, :, None], a5.shape)
    r = np.broadcast_to(rain.values[None], a5.shape)
    ok = np.isfinite(a5.values) & np.isfinite(r) & (r > WET_RAIN_MM_H) & np.isfinite(freq)
    meas, f, p, L, rr, k = a5.values[ok], freq[ok], pol[ok], length[ok], r[ok], link[ok]
    ours, p838 = predictions(f, p, L, rr)
    out: dict[str, Any] = {
        "links": links,
        "channels": n_ch,
        "intervals": int(ok.sum()),
        "groups": [],
    }
    for lo, hi in BANDS_GHZ:
        for pp in ("h", "v", "both"):
            sel = (f >= lo * 1e9) & (f < hi * 1e9) & ((p == pp) | (pp == "both"))
            if sel.sum() < 10:
                continue
            out["groups"].append({"band_ghz": [lo, hi], "pol": pp,
                                  "rainuav": stats(ours[sel], meas[sel]),
                                  "p838": stats(p838[sel], meas[sel])})  # fmt: skip
    out["all"] = {"rainuav": stats(ours, meas), "p838": stats(p838, meas)}
    out["_arrays"] = (meas, ours, p838, f, k)
    return out
