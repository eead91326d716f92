"""Serving cell, SIR and SINR from every cell's received power ([physics reference, section
5][5-radio-maps-sir-and-association])."""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

__all__ = ["RSS_FLOOR_DBM", "SIR_CEIL_DB", "SIR_FLOOR_DB", "sir_from_power"]

SIR_FLOOR_DB = -40.0
"""SIR and SINR where no cell reaches a pixel."""
SIR_CEIL_DB = 60.0
"""SIR and SINR ceiling (SIR where only one cell reaches)."""
RSS_FLOOR_DBM = -250.0
"""Received power recorded where a cell does not reach, dBm."""


def sir_from_power(
    power_mw: npt.NDArray[np.float64], noise_dbm: float
) -> tuple[npt.NDArray[np.int64], npt.NDArray[np.float64], npt.NDArray[np.float64]]:
    """The serving cell, SIR and SINR from every cell's received power.

    Args:
        power_mw: Received powers, mW, shape (M, H, W) for M cells.
        noise_dbm: The receiver's noise power, dBm.

    Returns:
        `(serving, sir_db, sinr_db)`, each (H, W): the strongest cell's index (-1 where none
        reaches), and the SIR and SINR in dB, clipped to [`SIR_FLOOR_DB`, `SIR_CEIL_DB`].
    """
    p = np.asarray(power_mw, dtype=np.float64)
    serving = np.argmax(p, axis=0)
    s = np.take_along_axis(p, serving[None], axis=0)[0]
    # Sums of powers spanning many decades can round below zero: clamp.
    interference = np.maximum(p.sum(axis=0) - s, 0.0)
    noise = 10.0 ** (noise_dbm / 10.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        sir = 10 * np.log10(s / interference)
        sinr = 10 * np.log10(s / (interference + noise))
    none = s <= 0
    sir = np.where(none, SIR_FLOOR_DB, np.where(interference <= 0, SIR_CEIL_DB, sir))
    sinr = np.where(none, SIR_FLOOR_DB, sinr)
    serving = np.where(none, -1, serving)
    return (
        serving.astype(np.int64),
        np.clip(sir, SIR_FLOOR_DB, SIR_CEIL_DB),
        np.clip(sinr, SIR_FLOOR_DB, SIR_CEIL_DB),
    )
