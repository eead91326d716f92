"""Outage as a probability on a [`Signal`][rainuav.signals.Signal] that carries every cell's power
and its spreads ([`CellPowers`][rainuav.cellpowers.CellPowers]): the same draws as
[`outage_probability()`][rainuav.radio.measured.outage.outage_probability] on a radio map, over
the signal's axes, so that the ``"chance"`` reward flies any signal that carries them (one
built from a map here, or read back from ``signal.npz``)."""

from __future__ import annotations

import dataclasses
from typing import TYPE_CHECKING

import numpy as np

from rainuav.cellpowers import CellPowers
from rainuav.errors import InvalidInputError
from rainuav.radio.measured.outage import DRAWS, _drawn_spreads, _outage_of

if TYPE_CHECKING:  # for the annotations alone
    from rainuav.radio.outputs.mapdata import RadioMap
    from rainuav.signals import Signal

__all__ = ["cell_powers", "signal_outage_probability", "with_cell_powers"]


def cell_powers(rm: RadioMap) -> CellPowers:
    """Every cell's power of one radio map and its spreads, over a signal's axes.

    The local mean's spread is split as the draws split it: the part every cell shares (a
    physics map's site error) and the rest, drawn cell by cell
    ([`rainuav.radio.measured.outage`][rainuav.radio.measured.outage]).

    Args:
        rm: The map: a corrected one with its own spreads, or a physics map (its prior's).

    Returns:
        The [`CellPowers`][rainuav.cellpowers.CellPowers], (C, 1, 1, 1, H, W).
    """
    local, one, common = _drawn_spreads(rm, None)
    lift = (slice(None), None, None, None)
    return CellPowers(np.asarray(rm.rss_dbm, dtype=float)[lift], local[lift], one[lift],
                      common, float(rm.scenario.noise_power_dbm))  # fmt: skip


def with_cell_powers(rm: RadioMap, signal: str = "sinr") -> Signal:
    """One radio map as a signal that carries every cell's power and its spreads.

    Args:
        rm: The map.
        signal: "sinr" or "sir".

    Returns:
        Its [`Signal`][rainuav.signals.Signal] (``as_signal``), its ``powers`` filled in.
    """
    return dataclasses.replace(rm.as_signal(signal, scenario_toml=False), powers=cell_powers(rm))


def signal_outage_probability(
    sig: Signal, min_db: float, seed: int = 0, draws: int = DRAWS, sample: bool = True
) -> np.ndarray:
    """The probability that the SINR is below a threshold, at every value of a signal.

    Every cell's power drawn from the signal's spreads, as
    [`outage_probability()`][rainuav.radio.measured.outage.outage_probability] draws a map's (on
    one map's signal, the same probabilities to the last bit).

    Args:
        sig: A signal that carries its cells' powers (``powers``).
        min_db: The SINR threshold, dB.
        seed: The draws' seed.
        draws: Draws per value (1-1 000 000).
        sample: One sample's outage (both spreads); False: the local mean's (its spread alone).

    Returns:
        The probability, the signal's values' shape (world, time, level, north, east).

    Raises:
        InvalidInputError: A signal without its cells' powers, or ``draws`` out of its range.
    """
    if sig.powers is None:
        raise InvalidInputError(
            "the signal carries no cells' powers and spreads (a radio map's: "
            "rainuav.radio.measured.signalrisk.with_cell_powers)"
        )
    if not 1 <= draws <= 1_000_000:
        raise InvalidInputError(f"draws must lie within 1..1000000 (got {draws})")
    pw = sig.powers
    sd = np.hypot(pw.local_std_db, pw.sample_std_db) if sample else pw.local_std_db
    m = pw.dbm.shape[0]
    out = _outage_of(pw.dbm.reshape(m, -1), sd.reshape(m, -1), pw.common_std_db,
                     pw.noise_power_dbm, min_db, draws, seed)  # fmt: skip
    return out.reshape(sig.values.shape)
