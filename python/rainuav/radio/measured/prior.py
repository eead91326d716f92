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

**Measured** (the default, [`MEASURED`][rainuav.radio.measured.prior.MEASURED] and
[`SITE_DB`][rainuav.radio.measured.prior.SITE_DB]). The published spreads are a statistical
model's; a physics map's own error is two things that these tables keep apart:

- the engine's error where it knows the scene and the antennas: measured against Sionna RT on
  the tracer scenes (``experiments/prior_spread_tracer.py``), per mechanism and per band of
  distance from the site (the error 68.27% of the tuning pixels stay within,
  [`measured_spreads()`][rainuav.radio.measured.prior.measured_spreads]): 0.3 dB in line of
  sight near the site to 4.6 dB beyond 700 m, 0.5-3.7 dB diffracted or reflected, 1.7-4.7 dB in
  deep shadow;
- the site database's error, which the engine cannot know (the transmit power, the real
  antenna patterns, cables, the airframe): 12.7 dB, chosen on real flights (AERPAW's, at the
  validation heights 30 and 70 m; ``experiments/aerpaw_flights.py``), added in quadrature.
  A truth whose sites are known exactly (a simulated one) takes ``model_db=0``.

The sample spreads are the standard deviation of the power in dB of a Ricean envelope of K = 7
dB (2.9 dB) and of a Rayleigh one (5.57 dB: ``10 / ln 10 * pi / sqrt 6``), computed in
[`fading_std_db()`][rainuav.radio.measured.prior.fading_std_db]; a receiver that averages
over a wide band (RSRP over every resource element) sees less. The local-mean spreads are the
published shadow fading of aerial users, the spread of a statistical model's map around the
truth. A physics map knows more than a statistical model where its scene is right, and less
where the scene or the antennas are wrong: the spreads a user should trust are the ones checked
on held-out data ("How far to trust a map": the real flights, the tracer's scenes)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
import numpy.typing as npt

from rainuav.errors import InvalidInputError
from rainuav.radio.measured.geometry import (
    excess_at,
    excess_loss_db,
    site_distance_at,
    site_distance_m,
)
from rainuav.radio.measured.rainspread import (
    RAIN_LOSS_DB,
    RAIN_SPREAD_DB,
    rain_loss_db,
    rain_spread_db,
    rain_spread_scores,
)

if TYPE_CHECKING:  # for the annotations alone
    from rainuav.radio.outputs.mapdata import RadioMap
    from rainuav.radio.scene.scenario import Scenario

__all__ = [
    "LOS_EXCESS_DB",
    "MEASURED",
    "MECHANISMS",
    "RAIN_LOSS_DB",
    "RAIN_SPREAD_DB",
    "SHADOW_EXCESS_DB",
    "SITE_DB",
    "SPREADS",
    "SPREAD_DISTANCES_M",
    "Spread",
    "engine_spread",
    "engine_spread_at",
    "excess_at",
    "excess_loss_db",
    "fading_std_db",
    "measured_spreads",
    "mechanism_of",
    "prior_spread",
    "rain_loss_db",
    "rain_spread_db",
    "rain_spread_scores",
    "site_distance_at",
    "site_distance_m",
    "spreads_of",
    "with_prior_spreads",
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

    local_db: float | tuple[float, ...]
    """The local mean's standard deviation, dB: one value, or one at each of
    [`SPREAD_DISTANCES_M`][rainuav.radio.measured.prior.SPREAD_DISTANCES_M] from the site
    (linear between, constant beyond)."""
    sample_db: float
    """One sample's standard deviation around the local mean, dB."""
    source: str
    """Where the values come from."""

    def local_at(self, distance_m: npt.ArrayLike) -> np.ndarray:
        """The local mean's spread at distances from the site, linear between the bands' middles.

        Args:
            distance_m: Distances, m.

        Returns:
            The spread, dB.
        """
        d = np.asarray(distance_m, dtype=float)
        if isinstance(self.local_db, tuple):
            return np.interp(d, SPREAD_DISTANCES_M, self.local_db)
        return np.full(d.shape, float(self.local_db))


def fading_std_db(k_db: float | None, draws: int = 400_000, seed: int = 0) -> float:
    """The standard deviation of `10 log10` of a unit-mean Ricean power, dB, by drawing.

    Rayleigh's exact value is `10 / ln(10) * pi / sqrt(6)` = 5.57 dB.

    Args:
        k_db: The K-factor, dB; None: Rayleigh.
        draws: Draws.
        seed: The draws' seed.

    Returns:
        The standard deviation, dB.
    """
    rng = np.random.default_rng(seed)
    k = 0.0 if k_db is None else 10 ** (k_db / 10)
    los = np.sqrt(k / (k + 1))
    scatter = np.sqrt(1 / (2 * (k + 1)))
    h = los + scatter * (rng.standard_normal(draws) + 1j * rng.standard_normal(draws))
    return float(np.std(10 * np.log10(np.abs(h) ** 2)))


SPREAD_DISTANCES_M = (50.0, 150.0, 300.0, 550.0, 1000.0)
"""The distances from the site, m, at which a measured table gives its local-mean spreads
(each the middle of a band: 0-100, 100-200, 200-400, 400-700 and beyond 700 m)."""
_BAND_EDGES_M = (0.0, 100.0, 200.0, 400.0, 700.0, np.inf)

SPREADS: dict[str, Spread] = {
    "line of sight": Spread(
        4.2, 2.9, "3GPP TR 36.777 Table B-2 (RMa-AV LOS); TR 38.901 Table 7.5-6 (RMa LOS K 7 dB)"
    ),
    "diffraction, reflection": Spread(
        6.0, 5.6, "3GPP TR 36.777 Table B-2 (RMa-AV, UMa-AV NLOS); Rayleigh fading"
    ),
    "deep shadow": Spread(8.0, 5.6, "3GPP TR 36.777 Table B-2 (UMi-AV NLOS); Rayleigh fading"),
}
"""The published spreads by mechanism (module docstring): a statistical model's."""

MEASURED: dict[str, Spread] = {
    "line of sight": Spread(
        (0.3, 0.7, 1.1, 1.9, 4.6), SPREADS["line of sight"].sample_db,
        "the ray engine against Sionna RT (tuning pixels); fading as published",
    ),
    "diffraction, reflection": Spread(
        (0.5, 3.4, 3.7, 3.7, 3.7), SPREADS["diffraction, reflection"].sample_db,
        "the ray engine against Sionna RT (tuning pixels); fading as published",
    ),
    "deep shadow": Spread(
        (1.7, 2.3, 4.7, 4.7, 4.7), SPREADS["deep shadow"].sample_db,
        "the ray engine against Sionna RT (tuning pixels); fading as published",
    ),
}  # fmt: skip
"""The engine's own local-mean error by mechanism and distance from the site, where it knows
the scene and the antennas (module docstring, "Measured"): the default table."""

SITE_DB = 12.7
"""The site database's error (transmit power, antenna pattern, cables, the airframe), dB, added
in quadrature to the local mean's spread of a map whose sites were never measured: chosen on
real flights (module docstring, "Measured"). Pass ``model_db=0`` for a scene whose sites are
known exactly (a simulated truth)."""


def spreads_of(
    excess_db: npt.ArrayLike,
    distance_m: npt.ArrayLike,
    model_db: float = 0.0,
    spreads: dict[str, Spread] | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """The local mean's and one sample's spreads at points of known excess loss and distance.

    By the mechanism the excess loss gives and the distance band (the module's docstring).

    Args:
        excess_db: Excess losses over free space, dB.
        distance_m: Distances from the site, m.
        model_db: The site database's error, dB, added to the local mean's in quadrature.
        spreads: The table; None: [`MEASURED`][rainuav.radio.measured.prior.MEASURED].

    Returns:
        `(local, sample)`, dB, of the points' shape.
    """
    table = MEASURED if spreads is None else spreads
    mech = mechanism_of(excess_db)
    dist = np.broadcast_to(np.asarray(distance_m, dtype=float), mech.shape)
    local = np.zeros(mech.shape)
    sample = np.zeros(mech.shape)
    for k, name in enumerate(MECHANISMS):
        m = mech == k
        local[m] = table[name].local_at(dist[m])
        sample[m] = table[name].sample_db
    return np.hypot(local, model_db), sample


def mechanism_of(excess_db: npt.ArrayLike) -> np.ndarray:
    """The mechanism of each excess loss: its index in `MECHANISMS`.

    Args:
        excess_db: Excess losses over free space, dB (NaN: a cell that does not reach).

    Returns:
        0 line of sight, 1 diffraction or reflection, 2 deep shadow (NaN's too).
    """
    e = np.asarray(excess_db, dtype=float)
    out = np.full(e.shape, 2, dtype=np.int8)
    out[e <= SHADOW_EXCESS_DB] = 1
    out[e <= LOS_EXCESS_DB] = 0
    return out


def measured_spreads(
    error_db: npt.ArrayLike,
    excess_db: npt.ArrayLike,
    distance_m: npt.ArrayLike,
    *,
    min_pixels: int = 50,
    floor_db: float = 0.3,
    source: str = "measured",
) -> dict[str, Spread]:
    """A table of local-mean spreads measured from a prediction's errors.

    Per mechanism and distance band, the error that 68.27% of the points stay within (bands of fewer
    than `min_pixels` points take their neighbours'), at least `floor_db` and never falling with
    distance; the sample spreads are the published ones, and a mechanism without enough points
    anywhere keeps the published spread (the module's docstring, "Measured").

    Args:
        error_db: Truth minus prediction at each point, dB.
        excess_db: The prediction's excess loss there, dB.
        distance_m: Its distance from the site, m.
        min_pixels: The fewest points a band is measured from.
        floor_db: The least spread, dB.
        source: The table's name in its entries.

    Returns:
        The table, by mechanism ([`Spread`][rainuav.radio.measured.prior.Spread] each).
    """
    e = np.abs(np.asarray(error_db, dtype=float)).ravel()
    mech = mechanism_of(excess_db).ravel()
    d = np.asarray(distance_m, dtype=float).ravel()
    ok = np.isfinite(e) & np.isfinite(d)
    out = {}
    for k, name in enumerate(MECHANISMS):
        row = np.full(len(SPREAD_DISTANCES_M), np.nan)
        for j in range(len(row)):
            m = ok & (mech == k) & (d >= _BAND_EDGES_M[j]) & (d < _BAND_EDGES_M[j + 1])
            if m.sum() >= min_pixels:
                row[j] = np.percentile(e[m], 68.27)
        have = ~np.isnan(row)
        if not have.any():
            out[name] = SPREADS[name]
            continue
        row = np.interp(SPREAD_DISTANCES_M, np.asarray(SPREAD_DISTANCES_M)[have], row[have])
        row = np.maximum.accumulate(np.maximum(row, floor_db))
        out[name] = Spread(tuple(round(float(v), 2) for v in row), SPREADS[name].sample_db,
                           source)  # fmt: skip
    return out


def with_prior_spreads(rm: RadioMap) -> Any:
    """A physics map carrying its prior's two spreads (its file, GeoTIFF and figures then say so).

    Args:
        rm: A physics map (not corrected by measurements).

    Returns:
        A copy with `rss_std_db` and `rss_sample_std_db` from
        [`prior_spread()`][rainuav.radio.measured.prior.prior_spread] (the defaults);
        `prior_rss_dbm` stays None.

    Raises:
        InvalidInputError: A map corrected by measurements (it has its own spreads).
    """
    import dataclasses

    if rm.prior_rss_dbm is not None:
        raise InvalidInputError("the map is corrected by measurements: it has its own spreads")
    local, sample = prior_spread(rm)
    return dataclasses.replace(rm, rss_std_db=local, rss_sample_std_db=sample)


def engine_spread_at(
    scn: Scenario,
    cell: int,
    x: npt.ArrayLike,
    y: npt.ArrayLike,
    z: npt.ArrayLike,
    power_dbm: npt.ArrayLike,
) -> np.ndarray:
    """The engine's own local-mean spread at points: how sure the physics is there.

    [`MEASURED`][rainuav.radio.measured.prior.MEASURED] by mechanism and distance, no site error:
    the scale of a corrected map's residual field
    ([`rainuav.radio.measured.residual`][rainuav.radio.measured.residual]).

    Args:
        scn: The scenario.
        cell: The cell's index.
        x: East, m.
        y: North, m.
        z: Height above sea level, m.
        power_dbm: The cell's power at the points, dBm.

    Returns:
        The spread, dB.
    """
    ex = excess_at(scn, cell, x, y, z, power_dbm)
    return spreads_of(ex, site_distance_at(scn, cell, x, y, z), 0.0)[0]


def engine_spread(rm: RadioMap) -> np.ndarray:
    """The engine's own local-mean spread at every pixel of every cell (no site error, no rain).

    Args:
        rm: The map.

    Returns:
        (M, H, W), dB: [`engine_spread_at()`][rainuav.radio.measured.prior.engine_spread_at] over
        the map's pixels.
    """
    return spreads_of(excess_loss_db(rm), site_distance_m(rm), 0.0)[0]


def prior_spread(
    rm: RadioMap,
    model_db: float = SITE_DB,
    spreads: dict[str, Spread] | None = None,
    pixels: npt.ArrayLike | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """A physics map's two spreads at every pixel of every cell: the local mean's and one sample's.

    By each pixel's mechanism and distance from its site (the module's docstring), the site
    database's error added to the local mean's in quadrature; a map in rain adds the spread of its
    rain loss ([`rain_spread_db()`][rainuav.radio.measured.rainspread.rain_spread_db] of
    [`rain_loss_db()`][rainuav.radio.measured.rainspread.rain_loss_db]) in quadrature.

    Args:
        rm: The physics map.
        model_db: The site database's error, 0-30 dB (default
            [`SITE_DB`][rainuav.radio.measured.prior.SITE_DB]; 0 for sites known exactly).
        spreads: The table; None: [`MEASURED`][rainuav.radio.measured.prior.MEASURED]
            ([`SPREADS`][rainuav.radio.measured.prior.SPREADS] for the published one).
        pixels: `(rows, columns)` to read at alone; None: every pixel.

    Returns:
        `(local, sample)`, dB, (M, H, W) each, or (M, N) at the `pixels`.

    Raises:
        InvalidInputError: `model_db` outside 0-30 dB.
    """
    if not 0.0 <= model_db <= 30.0:
        raise InvalidInputError(f"model_db must lie within 0..30 dB (got {model_db:g})")
    return composed_prior_spread(excess_loss_db(rm, pixels), site_distance_m(rm, pixels),
                                 rain_loss_db(rm, pixels), model_db, spreads)  # fmt: skip


def composed_prior_spread(
    excess_db: npt.ArrayLike,
    distance_m: npt.ArrayLike,
    rain_db: npt.ArrayLike,
    model_db: float = SITE_DB,
    spreads: dict[str, Spread] | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """[`prior_spread()`][rainuav.radio.measured.prior.prior_spread] from its parts.

    Args:
        excess_db: Each cell's excess loss at the pixels, dB.
        distance_m: Each cell's distance from its site there, m.
        rain_db: Each cell's loss to rain there, dB; None: clear air.
        model_db: The site database's error, dB.
        spreads: The table; None: `MEASURED`.

    Returns:
        `(local, sample)`, dB, of the parts' shape.
    """
    local, sample = spreads_of(excess_db, distance_m, model_db, spreads)
    if rain_db is not None:
        local = np.hypot(local, rain_spread_db(rain_db))
    return local, sample
