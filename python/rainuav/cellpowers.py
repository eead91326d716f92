"""Every cell's power and how far it is known, over a signal's axes: what a
[`Signal`][rainuav.signals.Signal] carries to draw its SINR (the outage probability of the
``"chance"`` reward and of ``fly``'s report).

A [`CellPowers`][rainuav.cellpowers.CellPowers] holds each cell's received power, dBm, over
``(cell, world, time, level, north, east)``, and the map's two spreads of it (the page "How far
to trust a map"): the **local mean's** (the uncertainty of the power a 10 m average sees), split
into the part drawn cell by cell (``local_std_db``) and the part every cell shares
(``common_std_db``, a physics map's site error: one draw for all cells), and **one sample's**
around the local mean (``sample_std_db``: fading, the airframe, the receiver). With the noise
power they give the SINR of every draw.

[`rainuav.radio.measured.signalrisk.with_cell_powers()`][rainuav.radio.measured.signalrisk.with_cell_powers]
fills them in from a radio map (its own spreads, or its prior's by mechanism), and
[`signal_outage_probability()`][rainuav.radio.measured.signalrisk.signal_outage_probability] draws
the SINR from them."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from rainuav.errors import InvalidInputError

__all__ = ["ARRAY_NAMES", "CellPowers"]

ARRAY_NAMES = (
    "cell_power_dbm",
    "cell_local_std_db",
    "cell_sample_std_db",
    "cell_common_std_db",
    "noise_power_dbm",
)
"""The names a signal file holds the cells' powers under (all of them, or none)."""


def _checked(name: str, a: Any, shape: tuple[int, ...], nonnegative: bool) -> np.ndarray:
    arr = np.asarray(a)
    if arr.ndim != len(shape) or arr.shape != shape or arr.dtype.kind != "f":
        raise InvalidInputError(
            f"{name} must be a floating array of shape {shape} (got {arr.dtype} of shape "
            f"{arr.shape})"
        )
    if not np.all(np.isfinite(arr)) or (nonnegative and np.any(arr < 0)):
        what = "finite and >= 0" if nonnegative else "finite"
        raise InvalidInputError(f"{name} must be {what} everywhere")
    arr = np.ascontiguousarray(arr, dtype=np.float64)
    arr.flags.writeable = False
    return arr


@dataclass(frozen=True, eq=False)
class CellPowers:
    """Each cell's power and its spreads over a signal's axes, checked when made (a field out of
    shape, not finite or a spread below 0 is one line naming it)."""

    dbm: npt.NDArray[np.float64]
    """(C, world, time, level, north, east): each cell's power, dBm (a floor where it does not
    reach)."""
    local_std_db: npt.NDArray[np.float64]
    """The shape of ``dbm``: the local mean's spread drawn cell by cell, dB."""
    sample_std_db: npt.NDArray[np.float64]
    """The shape of ``dbm``: one sample's spread around the local mean, dB."""
    common_std_db: float = 0.0
    """The local mean's spread every cell shares (one draw for all cells), dB."""
    noise_power_dbm: float = -100.0
    """The receiver's noise power, dBm."""

    def __post_init__(self) -> None:
        d = np.asarray(self.dbm)
        if d.ndim != 6 or min(d.shape) < 1:
            raise InvalidInputError(
                "dbm must be a 6-D array over (cell, world, time, level, north, east) "
                f"(got shape {d.shape})"
            )
        put = object.__setattr__  # frozen: the checked forms replace what was handed in
        put(self, "dbm", _checked("dbm", d, d.shape, False))
        for name in ("local_std_db", "sample_std_db"):
            put(self, name, _checked(name, getattr(self, name), d.shape, True))
        for name in ("common_std_db", "noise_power_dbm"):
            v = getattr(self, name)
            if not isinstance(v, int | float | np.floating) or not np.isfinite(v):
                raise InvalidInputError(f"{name} must be a finite number (got {v!r})")
            put(self, name, float(v))
        if self.common_std_db < 0:
            raise InvalidInputError(f"common_std_db must be >= 0 (got {self.common_std_db})")

    def fits(self, shape: tuple[int, ...]) -> None:
        """Checks that the powers lie over a signal's axes.

        Args:
            shape: The signal's values' shape (world, time, level, north, east).

        Raises:
            InvalidInputError: Powers over other axes.
        """
        if self.dbm.shape[1:] != tuple(shape):
            raise InvalidInputError(
                f"powers must be (cell, *{tuple(shape)}) over the signal's axes (got "
                f"{self.dbm.shape})"
            )

    def take(self, at: tuple[Any, ...]) -> CellPowers:
        """The powers at an index of the signal's axes (the cell axis kept).

        Args:
            at: One index or slice for each of the signal's five axes.

        Returns:
            A new [`CellPowers`][rainuav.cellpowers.CellPowers].
        """
        idx = (slice(None), *at)
        return CellPowers(self.dbm[idx], self.local_std_db[idx], self.sample_std_db[idx],
                          self.common_std_db, self.noise_power_dbm)  # fmt: skip

    def arrays(self) -> dict[str, Any]:
        """The arrays and numbers a signal file holds of them.

        Returns:
            By the names [`from_arrays()`][rainuav.cellpowers.CellPowers.from_arrays] reads.
        """
        values = (self.dbm, self.local_std_db, self.sample_std_db,
                  np.asarray(self.common_std_db), np.asarray(self.noise_power_dbm))  # fmt: skip
        return dict(zip(ARRAY_NAMES, values, strict=True))

    @classmethod
    def from_arrays(cls, data: dict[str, np.ndarray]) -> CellPowers | None:
        """The powers a signal file holds, or None where it holds none.

        Args:
            data: The file's arrays.

        Returns:
            The [`CellPowers`][rainuav.cellpowers.CellPowers], or None.

        Raises:
            InvalidInputError: Some of the arrays without the others, or out of range (named).
        """
        names = ARRAY_NAMES
        have = [n for n in names if n in data]
        if not have:
            return None
        if len(have) != len(names):
            raise InvalidInputError(
                f"the cells' powers need {list(names)} together (missing "
                f"{sorted(set(names) - set(have))})"
            )
        scalars = [np.asarray(data[n]) for n in names[3:]]
        if any(s.shape != () or s.dtype.kind != "f" for s in scalars):
            raise InvalidInputError("cell_common_std_db and noise_power_dbm must be numbers")
        return cls(data[names[0]], data[names[1]], data[names[2]], float(scalars[0]),
                   float(scalars[1]))  # fmt: skip
