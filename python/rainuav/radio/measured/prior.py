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

import itertools
from dataclasses import dataclass
from typing import Any

import numpy as np

from rainuav.errors import InvalidInputError
from rainuav.radio.outputs.sinr import RSS_FLOOR_DBM

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

    def local_at(self, distance_m: Any) -> np.ndarray:
        """The local mean's spread at each distance from the site, m, dB."""
        d = np.asarray(distance_m, dtype=float)
        if isinstance(self.local_db, tuple):
            return np.interp(d, SPREAD_DISTANCES_M, self.local_db)
        return np.full(d.shape, float(self.local_db))


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
    return excess_of(fs, power_dbm)


def excess_of(free_space_dbm: Any, power_dbm: Any) -> np.ndarray:
    """The excess loss of powers ``power_dbm`` over ``free_space_dbm``, dB; NaN at the floor."""
    p = np.asarray(power_dbm, dtype=float)
    return np.where(p > RSS_FLOOR_DBM + 1.0, free_space_dbm - p, np.nan)


def site_distance_at(scn: Any, cell: Any, x: Any, y: Any, z: Any) -> np.ndarray:
    """The distance from the antenna of the cell index ``cell`` to the points (``x``, ``y``,
    ``z``: east, north, height above sea level, m), m."""
    from rainuav.radio.measured.calibrate import _cells, _View

    site, c = _cells(scn)[int(cell)]
    v = _View(scn, site, c, x, y, z)
    return np.hypot(v.rho, v.dz)


def _pixel_points(rm: Any, pixels: Any) -> tuple[Any, np.ndarray, np.ndarray, np.ndarray]:
    from rainuav.radio.scene.terrain import flight_heights

    shape = np.shape(rm.rss_dbm)[1:]
    r, c = np.indices(shape) if pixels is None else (np.asarray(pixels[0]), np.asarray(pixels[1]))
    x, y = np.asarray(rm.x_m)[c].ravel(), np.asarray(rm.y_m)[r].ravel()
    z = np.broadcast_to(flight_heights(rm.scenario), shape)[r, c].ravel()
    return (r, c), x, y, z


def free_space_db(rm: Any, pixels: Any = None) -> np.ndarray:
    """Each cell's free-space power with its antenna gain at the ``pixels`` of ``rm``, dBm."""
    (r, _), x, y, z = _pixel_points(rm, pixels)
    zero = np.zeros_like(x)
    out = np.stack([excess_at(rm.scenario, k, x, y, z, zero) for k in range(len(rm.rss_dbm))])
    return out.reshape(len(rm.rss_dbm), *np.shape(r))


def excess_loss_db(rm: Any, pixels: Any = None) -> np.ndarray:
    """Each cell's excess loss over free space from its antenna, dB, at every pixel of the map
    ``rm`` at its flight height, (M, H, W), or at the ``pixels`` (rows, columns) alone, (M, N)
    (module docstring); NaN where the cell does not reach."""
    (r, c), *_ = _pixel_points(rm, pixels)
    return excess_of(free_space_db(rm, pixels), np.asarray(rm.rss_dbm, dtype=float)[:, r, c])


def site_distance_m(rm: Any, pixels: Any = None) -> np.ndarray:
    """Each cell's distance from its antenna, m, at every pixel of the map ``rm`` at its flight
    height, (M, H, W), or at the ``pixels`` (rows, columns) alone, (M, N)."""
    scn = rm.scenario
    m = len(rm.rss_dbm)
    (r, _), x, y, z = _pixel_points(rm, pixels)
    out = np.stack([site_distance_at(scn, k, x, y, z) for k in range(m)])
    return out.reshape(m, *np.shape(r))


def spreads_of(
    excess_db: Any, distance_m: Any, model_db: float = 0.0, spreads: dict[str, Spread] | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """The local mean's and one sample's spreads, dB, of pixels or points of excess losses
    ``excess_db`` at ``distance_m`` from their site (module docstring), ``model_db`` added to
    the first in quadrature; ``spreads``: the table (default
    [`MEASURED`][rainuav.radio.measured.prior.MEASURED])."""
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


def mechanism_of(excess_db: Any) -> np.ndarray:
    """The mechanism's index in ``MECHANISMS`` (0 line of sight, 1 diffraction or reflection,
    2 deep shadow) of each excess loss, dB (NaN, a cell that does not reach: deep shadow)."""
    e = np.asarray(excess_db, dtype=float)
    out = np.full(e.shape, 2, dtype=np.int8)
    out[e <= SHADOW_EXCESS_DB] = 1
    out[e <= LOS_EXCESS_DB] = 0
    return out


def measured_spreads(
    error_db: Any, excess_db: Any, distance_m: Any, *, min_pixels: int = 50,
    floor_db: float = 0.3, source: str = "measured",
) -> dict[str, Spread]:  # fmt: skip
    """A table of local-mean spreads measured from a prediction's errors (``error_db``, truth
    minus prediction) at points of excess losses ``excess_db`` and distances ``distance_m``
    (module docstring, "Measured"): per mechanism and distance band, the error that 68.27% of
    the points stay within (bands of fewer than ``min_pixels`` points take their neighbours'),
    at least ``floor_db`` and never falling with distance; the sample spreads the published
    ones. A mechanism without enough points anywhere keeps the published spread."""
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


RAIN_LOSS_DB = (0.5, 1.0, 2.0, 4.0, 8.0, 16.0)
"""The edges of the bands of rain loss, dB, of
[`RAIN_SPREAD_DB`][rainuav.radio.measured.prior.RAIN_SPREAD_DB] (0-0.5, 0.5-1, ..., beyond 16)."""
RAIN_SPREAD_DB = (0.26, 0.77, 1.39, 2.36, 3.82, 6.69, 17.13)
"""The spread of a predicted rain loss in each band of ``RAIN_LOSS_DB``, dB: the error that
68.27% of real links' five-minute rain losses in the band stay within, predicted by the medium
from radar rain (pycomlink's 500 German links, those of even index;
[`rain_spread_scores()`][rainuav.radio.measured.prior.rain_spread_scores]). About 0.6 times
the loss up to 16 dB."""


def rain_spread_db(loss_db: Any) -> np.ndarray:
    """The spread of predicted rain losses ``loss_db``, dB (their band's; 0 for no loss)."""
    a = np.nan_to_num(np.asarray(loss_db, dtype=float))
    out = np.asarray(RAIN_SPREAD_DB)[np.searchsorted(RAIN_LOSS_DB, a, side="right")]
    return np.where(a > 0, out, 0.0)


def with_prior_spreads(rm: Any) -> Any:
    """The physics map ``rm`` carrying its prior's two spreads
    ([`prior_spread()`][rainuav.radio.measured.prior.prior_spread], the defaults) as
    ``rss_std_db`` and ``rss_sample_std_db``, so that its file, GeoTIFF and figures say how sure
    it is (``prior_rss_dbm`` stays None: a physics map, not a corrected one)."""
    import dataclasses

    if rm.prior_rss_dbm is not None:
        raise InvalidInputError("the map is corrected by measurements: it has its own spreads")
    local, sample = prior_spread(rm)
    return dataclasses.replace(rm, rss_std_db=local, rss_sample_std_db=sample)


def rain_spread_scores(
    measured_db: Any, predicted_db: Any, link: Any
) -> dict[str, Any]:  # fmt: skip
    """The spread of predicted rain losses measured on real links: ``measured_db`` and
    ``predicted_db`` the losses of each interval, ``link`` its link's index (as
    ``rainuav.cml.compare`` gives them in ``_arrays``). Per band of predicted loss
    (``RAIN_LOSS_DB``), the error (measured minus predicted) that 68.27% of the intervals of the
    links of even index stay within (``tuned``: what ``RAIN_SPREAD_DB`` holds); and
    ``RAIN_SPREAD_DB`` scored on the links of odd index, which it never saw (``held_out``:
    intervals, shares within one and two sigma, CRPS with and without the spread, dB, and the
    share within one sigma by band)."""
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


def rain_loss_db(rm: Any, pixels: Any = None) -> np.ndarray | None:
    """Each cell's loss to rain at every pixel of the map ``rm``, dB, (M, H, W) (at the
    ``pixels`` alone: (M, N)): the same scenario's map in clear air (built, or from the cache)
    less this one; None for a map in clear air."""
    clear = clear_air_power_dbm(rm)
    if clear is None:
        return None
    wet = np.asarray(rm.rss_dbm, dtype=float)
    at = (slice(None),) if pixels is None else (slice(None), pixels[0], pixels[1])
    return rain_loss_of(clear[at], wet[at])


def rain_loss_of(clear_dbm: Any, wet_dbm: Any) -> np.ndarray:
    """The loss to rain of powers ``wet_dbm`` against ``clear_dbm``, dB; 0 at the floor."""
    wet = np.asarray(wet_dbm, dtype=float)
    return np.where(wet > RSS_FLOOR_DBM + 1.0, np.maximum(clear_dbm - wet, 0.0), 0.0)


def clear_air_power_dbm(rm: Any) -> np.ndarray | None:
    """Each cell's power over ``rm``'s pixels in clear air, dBm (built or cached); None if clear."""
    scn = rm.scenario
    med = scn.medium
    if med.kind == "clear" or (med.kind == "homogeneous" and med.rain_rate_mm_h == 0):
        return None
    from rainuav.radio.outputs.maps import build_radio_map
    from rainuav.radio.scene.weather import Medium

    return np.asarray(build_radio_map(scn.replace(medium=Medium(kind="clear"))).rss_dbm, float)


def engine_spread_at(scn: Any, cell: Any, x: Any, y: Any, z: Any, power_dbm: Any) -> np.ndarray:
    """The engine's own local-mean spread ([`MEASURED`][rainuav.radio.measured.prior.MEASURED],
    no site error) at the points (``x``, ``y``, ``z``: east, north, height above sea level, m)
    whose powers of the cell index ``cell`` are ``power_dbm``, dB: how sure the physics is
    there, by mechanism and distance (the scale of a corrected map's residual field,
    [`rainuav.radio.measured.residual`][rainuav.radio.measured.residual])."""
    ex = excess_at(scn, cell, x, y, z, power_dbm)
    return spreads_of(ex, site_distance_at(scn, cell, x, y, z), 0.0)[0]


def engine_spread(rm: Any) -> np.ndarray:
    """The engine's own local-mean spread at every pixel of every cell of the map ``rm``, dB,
    (M, H, W): [`engine_spread_at()`][rainuav.radio.measured.prior.engine_spread_at] over the
    map's pixels (no site error, no rain)."""
    return spreads_of(excess_loss_db(rm), site_distance_m(rm), 0.0)[0]


def prior_spread(
    rm: Any, model_db: float = SITE_DB, spreads: dict[str, Spread] | None = None,
    pixels: Any = None,
) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """The physics map ``rm``'s two spreads at every pixel of every cell, (M, H, W) each (at the
    ``pixels`` (rows, columns) alone: (M, N)), dB: the local mean's and one sample's (module
    docstring), by each pixel's mechanism and distance from its site; ``model_db`` (0-30 dB,
    default the site database's error [`SITE_DB`][rainuav.radio.measured.prior.SITE_DB]) is
    added to the local mean's in quadrature; ``spreads``: the table (default
    [`MEASURED`][rainuav.radio.measured.prior.MEASURED];
    [`SPREADS`][rainuav.radio.measured.prior.SPREADS] for the published one). A map in rain
    adds the spread of its rain loss
    ([`rain_spread_db()`][rainuav.radio.measured.prior.rain_spread_db] of
    [`rain_loss_db()`][rainuav.radio.measured.prior.rain_loss_db]) in quadrature."""
    if not 0.0 <= model_db <= 30.0:
        raise InvalidInputError(f"model_db must lie within 0..30 dB (got {model_db:g})")
    return composed_prior_spread(excess_loss_db(rm, pixels), site_distance_m(rm, pixels),
                                 rain_loss_db(rm, pixels), model_db, spreads)  # fmt: skip


def composed_prior_spread(
    excess_db: Any, distance_m: Any, rain_db: Any, model_db: float = SITE_DB,
    spreads: dict[str, Spread] | None = None,
) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """[`prior_spread()`][rainuav.radio.measured.prior.prior_spread] from its parts."""
    local, sample = spreads_of(excess_db, distance_m, model_db, spreads)
    if rain_db is not None:
        local = np.hypot(local, rain_spread_db(rain_db))
    return local, sample
