"""How far a physics map is to be trusted before anything is measured: the prior's two spreads
at every pixel, by the mechanism that carries the power there.

A map's power at a pixel is a **local mean**: the power averaged over a few wavelengths to a
few metres, where fast fading averages out. Two spreads describe a prediction of it:

- ``local_std_db``: the uncertainty of the local mean itself: what the physics does not know
  (shadowing by what the scene does not hold, the antennas' real patterns and the airframe,
  the site database's errors);
- ``sample_std_db``: the spread of one sample around the local mean (multipath fading, the
  receiver's error). A link's outage happens sample by sample and uses both, in quadrature; a
  local average uses the first alone.

**Mechanism.** The engines do not label their paths, but the power says what reached the pixel:
its excess loss over free space from the cell's antenna (its gain toward the pixel),
``excess = P_fs - P_map``, dB. Up to ``LOS_EXCESS_DB`` the pixel is in line of sight (the
direct ray with a ground reflection, which swings the power a few dB either way); to
``SHADOW_EXCESS_DB`` it is reached by diffraction (over roofs, terrain, corners) or by
reflections; beyond, it is in deep shadow. Rain's attenuation counts as excess loss too, and a
rain-soaked link is uncertain by more than a clear one.

**Spreads by mechanism** ([`SPREADS`][rainuav.radio.measured.prior.SPREADS]):

| mechanism | local mean, dB | one sample, dB | source |
|---|---|---|---|
| line of sight | 4.2 | 2.9 | TR 36.777 B-2 (RMa-AV LOS); TR 38.901 7.5-6 (RMa LOS K 7 dB) |
| diffraction, reflection | 6.0 | 5.6 | TR 36.777 B-2 (RMa-AV, UMa-AV NLOS); Rayleigh |
| deep shadow | 8.0 | 5.6 | TR 36.777 B-2 (UMi-AV NLOS); Rayleigh |

(3GPP TR 36.777 Table B-2: the shadow fading of aerial users; TR 38.901 Table 7.5-6: the
Ricean K-factor.)

The sample spreads are the standard deviation of the power in dB of a Ricean envelope of K = 7
dB (2.9 dB) and of a Rayleigh one (5.57 dB: ``10 / ln 10 * pi / sqrt 6``), computed in
[`fading_std_db()`][rainuav.radio.measured.prior.fading_std_db]; a receiver that averages
over a wide band (RSRP over every resource element) sees less. The local-mean spreads are the
published shadow fading of aerial users, the spread of a statistical model's map around the
truth. A physics map knows more than a statistical model where its scene is right, and less
where the scene or the antennas are wrong: the spreads a user should trust are the ones checked
on held-out data ("How far to trust a map": the real flights, the tracer's scenes), and
[`prior_spread()`][rainuav.radio.measured.prior.prior_spread] takes a ``model_db`` that adds the
engine's own error in quadrature."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from rainuav.errors import InvalidInputError
from rainuav.radio.outputs.sinr import RSS_FLOOR_DBM

__all__ = [
    "LOS_EXCESS_DB",
    "MECHANISMS",
    "SHADOW_EXCESS_DB",
    "SPREADS",
    "Spread",
    "excess_at",
    "excess_loss_db",
    "fading_std_db",
    "mechanism_of",
    "prior_spread",
    "spreads_of",
]

LOS_EXCESS_DB = 3.0
"""The most excess loss over free space of a pixel in line of sight, dB."""
SHADOW_EXCESS_DB = 20.0
"""The excess loss beyond which a pixel is in deep shadow, dB."""
MECHANISMS = ("line of sight", "diffraction, reflection", "deep shadow")
"""The mechanisms, in the order of [`mechanism_of()`][rainuav.radio.measured.prior.mechanism_of]."""


@dataclass(frozen=True)
class Spread:
    """The prior's two spreads for one mechanism, dB, and where they come from."""

    local_db: float
    """The local mean's standard deviation, dB."""
    sample_db: float
    """One sample's standard deviation around the local mean, dB."""
    source: str
    """The published tables the values come from."""


def fading_std_db(k_db: float | None, draws: int = 400_000, seed: int = 0) -> float:
    """The standard deviation of ``10 log10`` of a unit-mean Ricean power of K-factor ``k_db``
    (None: Rayleigh), dB, by drawing (``draws`` draws from ``seed``; Rayleigh's exact value is
    ``10 / ln(10) * pi / sqrt(6)`` = 5.57 dB)."""
    rng = np.random.default_rng(seed)
    k = 0.0 if k_db is None else 10 ** (k_db / 10)
    los = np.sqrt(k / (k + 1))
    scatter = np.sqrt(1 / (2 * (k + 1)))
    h = los + scatter * (rng.standard_normal(draws) + 1j * rng.standard_normal(draws))
    return float(np.std(10 * np.log10(np.abs(h) ** 2)))


SPREADS: dict[str, Spread] = {
    "line of sight": Spread(
        4.2, 2.9, "3GPP TR 36.777 Table B-2 (RMa-AV LOS); TR 38.901 Table 7.5-6 (RMa LOS K 7 dB)"
    ),
    "diffraction, reflection": Spread(
        6.0, 5.6, "3GPP TR 36.777 Table B-2 (RMa-AV, UMa-AV NLOS); Rayleigh fading"
    ),
    "deep shadow": Spread(8.0, 5.6, "3GPP TR 36.777 Table B-2 (UMi-AV NLOS); Rayleigh fading"),
}
"""The prior's spreads by mechanism (module docstring)."""


def excess_at(scn: Any, cell: Any, x: Any, y: Any, z: Any, power_dbm: Any) -> np.ndarray:
    """The excess loss over free space of the powers ``power_dbm`` of the cell index ``cell``
    at the points (``x``, ``y``, ``z``: east, north, height above sea level, m), dB; NaN where
    a power is the floor's (module docstring)."""
    from rainuav.radio.measured.calibrate import _cells, _View

    site, c = _cells(scn)[int(cell)]
    v = _View(scn, site, c, x, y, z)
    lam = 299_792_458.0 / scn.freq_hz
    d = np.maximum(np.hypot(v.rho, v.dz), lam)
    fs = c.tx_power_dbm + v.g0 - 20 * np.log10(4 * np.pi * d / lam)
    p = np.asarray(power_dbm, dtype=float)
    return np.where(p > RSS_FLOOR_DBM + 1.0, fs - p, np.nan)


def excess_loss_db(rm: Any, pixels: Any = None) -> np.ndarray:
    """Each cell's excess loss over free space from its antenna, dB, at every pixel of the map
    ``rm`` at its flight height, (M, H, W), or at the ``pixels`` (rows, columns) alone, (M, N)
    (module docstring); NaN where the cell does not reach."""
    from rainuav.radio.scene.terrain import flight_heights

    scn = rm.scenario
    rss = np.asarray(rm.rss_dbm, dtype=float)
    shape = rss.shape[1:]
    r, c = np.indices(shape) if pixels is None else (np.asarray(pixels[0]), np.asarray(pixels[1]))
    x, y = np.asarray(rm.x_m)[c].ravel(), np.asarray(rm.y_m)[r].ravel()
    z = np.broadcast_to(flight_heights(scn), shape)[r, c].ravel()
    out = np.stack([excess_at(scn, k, x, y, z, rss[k][r, c].ravel()) for k in range(len(rss))])
    return out.reshape(len(rss), *np.shape(r))


def spreads_of(
    excess_db: Any, model_db: float = 0.0, spreads: dict[str, Spread] | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """The local mean's and one sample's spreads, dB, of pixels or points of excess losses
    ``excess_db`` (module docstring), ``model_db`` added to the first in quadrature."""
    table = spreads or SPREADS
    mech = mechanism_of(excess_db)
    local = np.array([table[k].local_db for k in MECHANISMS])[mech]
    sample = np.array([table[k].sample_db for k in MECHANISMS])[mech]
    return np.hypot(local, model_db), sample


def mechanism_of(excess_db: Any) -> np.ndarray:
    """The mechanism's index in ``MECHANISMS`` (0 line of sight, 1 diffraction or reflection,
    2 deep shadow) of each excess loss, dB (NaN, a cell that does not reach: deep shadow)."""
    e = np.asarray(excess_db, dtype=float)
    out = np.full(e.shape, 2, dtype=np.int8)
    out[e <= SHADOW_EXCESS_DB] = 1
    out[e <= LOS_EXCESS_DB] = 0
    return out


def prior_spread(
    rm: Any, model_db: float = 0.0, spreads: dict[str, Spread] | None = None, pixels: Any = None
) -> tuple[np.ndarray, np.ndarray]:
    """The physics map ``rm``'s two spreads at every pixel of every cell, (M, H, W) each (at the
    ``pixels`` (rows, columns) alone: (M, N)), dB: the local mean's and one sample's (module
    docstring), by each pixel's mechanism; ``model_db`` (0-30 dB) is added to the local mean's
    in quadrature (an engine's own error, measured on held-out data)."""
    if not 0.0 <= model_db <= 30.0:
        raise InvalidInputError(f"model_db must lie within 0..30 dB (got {model_db:g})")
    return spreads_of(excess_loss_db(rm, pixels), model_db, spreads)
