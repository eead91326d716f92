"""The spread of a predicted rain loss, which a map in rain adds to the prior's local-mean spread
(measured on real links:
[`rain_spread_scores()`][rainuav.radio.measured.rainspread.rain_spread_scores]), and the loss
itself: the same map in clear air less this one."""

from __future__ import annotations

import itertools
from typing import TYPE_CHECKING, Any

import numpy as np
import numpy.typing as npt

from rainuav.radio.outputs.sinr import RSS_FLOOR_DBM

if TYPE_CHECKING:  # for the annotations alone
    from rainuav.radio.outputs.mapdata import RadioMap

__all__ = [
    "RAIN_LOSS_DB",
    "RAIN_SPREAD_DB",
    "clear_air_power_dbm",
    "rain_loss_db",
    "rain_loss_of",
    "rain_spread_db",
    "rain_spread_scores",
]


RAIN_LOSS_DB = (0.5, 1.0, 2.0, 4.0, 8.0, 16.0)
"""The edges of the bands of rain loss, dB, of
[`RAIN_SPREAD_DB`][rainuav.radio.measured.rainspread.RAIN_SPREAD_DB] (0-0.5, 0.5-1, ..., beyond
16)."""
RAIN_SPREAD_DB = (0.26, 0.77, 1.39, 2.36, 3.82, 6.69, 17.13)
"""The spread of a predicted rain loss in each band of ``RAIN_LOSS_DB``, dB: the error that
68.27% of real links' five-minute rain losses in the band stay within, predicted by the medium
from radar rain (pycomlink's 500 German links, those of even index;
[`rain_spread_scores()`][rainuav.radio.measured.rainspread.rain_spread_scores]). About 0.6 times
the loss up to 16 dB."""


def rain_spread_db(loss_db: npt.ArrayLike) -> np.ndarray:
    """The spread of predicted rain losses: their band's.

    Args:
        loss_db: Predicted losses, dB (NaN taken as 0).

    Returns:
        The spreads, dB ([`RAIN_SPREAD_DB`][rainuav.radio.measured.rainspread.RAIN_SPREAD_DB] by
        band; 0 for no loss).
    """
    a = np.nan_to_num(np.asarray(loss_db, dtype=float))
    out = np.asarray(RAIN_SPREAD_DB)[np.searchsorted(RAIN_LOSS_DB, a, side="right")]
    return np.where(a > 0, out, 0.0)


def rain_spread_scores(
    measured_db: npt.ArrayLike, predicted_db: npt.ArrayLike, link: npt.ArrayLike
) -> dict[str, Any]:  # fmt: skip
    """The spread of predicted rain losses measured on real links, and scored on others.

    Per band of predicted loss (`RAIN_LOSS_DB`), the error (measured minus predicted) that 68.27% of
    the intervals of the links of even index stay within (what `RAIN_SPREAD_DB` holds); then
    `RAIN_SPREAD_DB` scored on the links of odd index, which it never saw.

    Args:
        measured_db: Each interval's measured loss, dB.
        predicted_db: Each interval's predicted loss, dB.
        link: Each interval's link index (as `rainuav.cml.compare` gives them in `_arrays`).

    Returns:
        `tuned` (each band's spread, None below 50 intervals) and `held_out` (the intervals, the
        shares within one and two sigma, the CRPS with and without the spread, dB, and the share
        within one sigma by band).
    """
    from rainuav.radio.measured.scores import crps_gaussian

    meas, ours = np.asarray(measured_db, float), np.asarray(predicted_db, float)
    err = meas - ours
    tune = np.asarray(link) % 2 == 0
    edges = (0.0, *RAIN_LOSS_DB, np.inf)
    tuned = []
    for lo, hi in itertools.pairwise(edges):
        m = tune & (ours >= lo) & (ours < hi)
        tuned.append(float(np.percentile(np.abs(err[m]), 68.27)) if m.sum() >= 50 else None)
    held = ~tune
    sd, e, pred = rain_spread_db(ours[held]), err[held], ours[held]
    by_band = []
    for lo, hi in itertools.pairwise(edges):
        m = (pred >= lo) & (pred < hi)
        if m.any():
            by_band.append({"loss_db": [lo, None if np.isinf(hi) else hi],
                            "intervals": int(m.sum()),
                            "within_one_sigma": float(np.mean(np.abs(e[m]) <= sd[m]))})  # fmt: skip
    return {"tuned": tuned, "held_out": {
        "intervals": int(held.sum()),
        "within_one_sigma": float(np.mean(np.abs(e) <= sd)),
        "within_two_sigma": float(np.mean(np.abs(e) <= 2 * sd)),
        "crps_db": float(np.mean(crps_gaussian(e, 0.0, sd))),
        "crps_no_spread_db": float(np.mean(np.abs(e))),
        "by_band": by_band,
    }}  # fmt: skip


def rain_loss_db(rm: RadioMap, pixels: npt.ArrayLike | None = None) -> np.ndarray | None:
    """Each cell's loss to rain at a map's pixels: the same scenario's clear-air map less this one.

    Args:
        rm: The map (the clear-air map is built, or taken from the cache).
        pixels: `(rows, columns)` to read at alone; None: every pixel.

    Returns:
        (M, H, W), or (M, N) at the `pixels`, dB; None for a map in clear air.
    """
    clear = clear_air_power_dbm(rm)
    if clear is None:
        return None
    wet = np.asarray(rm.rss_dbm, dtype=float)
    at = (slice(None),) if pixels is None else (slice(None), pixels[0], pixels[1])
    return rain_loss_of(clear[at], wet[at])


def rain_loss_of(clear_dbm: npt.ArrayLike, wet_dbm: npt.ArrayLike) -> np.ndarray:
    """The loss to rain of powers against their clear-air powers, dB.

    Args:
        clear_dbm: The clear-air powers, dBm.
        wet_dbm: The powers in rain, dBm.

    Returns:
        The losses, at least 0; 0 where a power in rain is the floor's.
    """
    wet = np.asarray(wet_dbm, dtype=float)
    return np.where(wet > RSS_FLOOR_DBM + 1.0, np.maximum(clear_dbm - wet, 0.0), 0.0)


def clear_air_power_dbm(rm: RadioMap) -> np.ndarray | None:
    """Each cell's power over a map's pixels in clear air, dBm (built, or taken from the cache).

    Args:
        rm: The map.

    Returns:
        (M, H, W), or None where the map is in clear air already.
    """
    scn = rm.scenario
    med = scn.medium
    if med.kind == "clear" or (med.kind == "homogeneous" and med.rain_rate_mm_h == 0):
        return None
    from rainuav.radio.outputs.maps import build_radio_map
    from rainuav.radio.scene.weather import Medium

    return np.asarray(build_radio_map(scn.replace(medium=Medium(kind="clear"))).rss_dbm, float)
