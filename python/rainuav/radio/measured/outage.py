"""Outage as a probability on any map: P(SINR < threshold) at every pixel, and what it makes of a
path.

Each cell's power at a pixel is uncertain by its spreads
([`map_spreads()`][rainuav.radio.measured.outage.map_spreads]): a map corrected by measurements
carries them (``rss_std_db``, the local mean's, and ``rss_sample_std_db``, one sample's); a
physics map has its prior's by mechanism
([`rainuav.radio.measured.prior`][rainuav.radio.measured.prior]). A link's outage happens sample by
sample, so a draw of one cell's power is Gaussian in dB with both spreads in quadrature
(``sample=False``: the local mean's alone, an outage of the average), independent between cells
but for a physics map's site database error
([`SITE_DB`][rainuav.radio.measured.prior.SITE_DB]), drawn once a draw for every cell: what the
UAV's antenna, airframe and receiver add is the same for every cell, and independent errors of
that size would promise a diversity (some cell always strong) that no network has. A draw is
capped at 100 dBm, the maps' own ceiling. The serving cell, the
interference and so the SINR follow from all of them together (a draw may change which cell
serves), so the probability is estimated by drawing:
``DRAWS`` draws of every cell's power at each pixel (one seed, so the same map gives the same
probabilities), the SINR of each draw as
[`sir_from_power()`][rainuav.radio.outputs.sinr.sir_from_power] computes it, and the share below
the threshold (a standard error of at most ``0.5 / sqrt(draws)``: 0.031 at the default
256). The task's ``"chance"`` reward reads them (``rainuav.nav.task``: a move costs ``1 + mu P``,
the ``"outage"`` reward's expectation; ``rainuav.world.world_from`` puts them in the field of a
map, for the exact planner and the environment)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np
import numpy.typing as npt

from rainuav.errors import InvalidInputError
from rainuav.radio.measured.prior import SITE_DB
from rainuav.radio.outputs.sinr import RSS_FLOOR_DBM, sir_from_power

if TYPE_CHECKING:  # for the annotations alone
    from rainuav.radio.outputs.mapdata import RadioMap
    from rainuav.radio.outputs.timemap import RadioMapSeries

__all__ = [
    "DRAWS",
    "flight_outage_among_levels",
    "flight_outage_in_time",
    "map_spreads",
    "outage_probability",
    "path_outage",
    "path_outage_draws",
]

DRAWS = 256
"""Draws per pixel (a whole 200 x 200 map of 21 cells in about 10 s on 2 cores)."""


def map_spreads(rm: RadioMap, pixels: npt.ArrayLike | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The local mean's and one sample's spread of every cell's power at every pixel of a map, dB.

    Those the map carries (a corrected map's own, or a physics map's prior ones written with it; a
    map saved without the sample spread: 0 for it), else the prior's by mechanism
    ([`prior_spread()`][rainuav.radio.measured.prior.prior_spread]).

    Args:
        rm: The map.
        pixels: `(rows, columns)` to read at alone; None: every pixel.

    Returns:
        `(local, sample)`, (M, H, W) each, or (M, N) at the `pixels`.
    """
    if getattr(rm, "rss_std_db", None) is not None:
        local = np.asarray(rm.rss_std_db, dtype=float)
        sample = getattr(rm, "rss_sample_std_db", None)
        one = np.zeros_like(local) if sample is None else np.asarray(sample, float)
        if pixels is not None:
            local, one = local[:, pixels[0], pixels[1]], one[:, pixels[0], pixels[1]]
        return local, one
    from rainuav.radio.measured.prior import prior_spread

    return prior_spread(rm, pixels=pixels)


def _drawn_spreads(rm: RadioMap, pixels: npt.ArrayLike) -> tuple[np.ndarray, np.ndarray, float]:
    """How a draw spreads each cell's power (module docstring): the local mean's spread drawn
    cell by cell, one sample's, and the part shared by every cell (a physics map's site error,
    taken out of the first in quadrature; 0 for a corrected map)."""
    local, one = map_spreads(rm, pixels)
    common = SITE_DB if getattr(rm, "prior_rss_dbm", None) is None else 0.0
    return _less(local, common), one, common


def _less(local: np.ndarray, common: float) -> np.ndarray:
    """The part of the local mean's spread ``local`` drawn cell by cell: ``common`` (drawn once
    for every cell) taken out in quadrature."""
    return np.sqrt(np.maximum(local**2 - common**2, 0.0))


def _outage_of(
    mean: np.ndarray,
    dev: np.ndarray,
    common: float,
    noise_dbm: float,
    min_db: float,
    draws: int,
    seed: int,
) -> np.ndarray:
    """P(SINR < ``min_db``) of points whose cells' powers are ``mean`` (M, N), dB, each drawn
    with its own deviation ``dev`` (M, N) and ``common`` shared by every cell (module
    docstring)."""
    rng = np.random.default_rng(seed)
    m, n = mean.shape
    reached = mean > RSS_FLOOR_DBM + 1.0
    out = np.empty(n)
    chunk = max(1, int(4e7 // (draws * m)))
    for i in range(0, n, chunk):
        s = slice(i, i + chunk)
        k = mean[:, s].shape[1]
        # float32 draws: a power's tenth of a dB is far below its deviation, and half the time
        z = rng.standard_normal((draws, m, k), dtype=np.float32)
        d = mean[None, :, s].astype(np.float32) + dev[None, :, s].astype(np.float32) * z
        if common:  # one draw a pixel for every cell
            d += np.float32(common) * rng.standard_normal((draws, 1, k), dtype=np.float32)
        d = np.minimum(d, np.float32(100.0))
        p = np.where(reached[None, :, s], np.exp(d * np.float32(np.log(10) / 10)), 0.0)
        sinr = sir_from_power(p.transpose(1, 0, 2).reshape(m, -1), noise_dbm)[2]
        out[s] = (sinr.reshape(draws, k) < min_db).mean(axis=0)
    return out


def flight_outage_in_time(
    series: RadioMapSeries,
    path_m: npt.ArrayLike,
    t_s: npt.ArrayLike,
    min_db: float,
    *,
    draws: int = 4096,
    seed: int = 0,
) -> np.ndarray:
    """The outage probability of each move of a flight through a weather that moves.

    The move ending at ``path_m[k]`` at ``t_s[k]`` is read on the slice of ``series`` nearest
    that instant (the slices are 5 s apart in a flight plan: a few moves), with that slice's
    prior spreads, as [`outage_probability()`][rainuav.radio.measured.outage.outage_probability]
    draws them on that slice's map; the geometry of the spreads (each cell's free-space power and
    distance at the path's pixels) and the clear-air map are computed once for every slice.

    Args:
        series: A [`RadioMapSeries`][rainuav.radio.RadioMapSeries] (a physics map in time).
        path_m: Where each move ends, (N, 2), m.
        t_s: When each move ends, (N,), s.
        min_db: The SINR threshold, dB.
        draws: Draws per move (1-1 000 000).
        seed: The draws' seed.

    Returns:
        One sample's outage probability at each move, (N,).

    Raises:
        InvalidInputError: ``draws`` out of its range.
    """
    from rainuav._sampling import pixel_index
    from rainuav.radio.measured.geometry import excess_of, free_space_db, site_distance_m
    from rainuav.radio.measured.prior import composed_prior_spread
    from rainuav.radio.measured.rainspread import clear_air_power_dbm, rain_loss_of

    if not 1 <= draws <= 1_000_000:
        raise InvalidInputError(f"draws must lie within 1..1000000 (got {draws})")
    path = np.asarray(path_m, dtype=float).reshape(-1, 2)
    slot = np.abs(np.asarray(t_s, float)[:, None] - np.asarray(series.t_s)[None, :]).argmin(1)
    first = series.at(float(series.t_s[0]))  # the grid and the geometry of every slice
    r, c = pixel_index(first.sinr_db.shape, first.extent_m, path[:, 0], path[:, 1])
    # (M, N): each move on its slice; indexed first, so the whole series is never copied
    power = np.asarray(series.rss_dbm)[slot, :, r, c].astype(np.float64).T
    excess = excess_of(free_space_db(first, (r, c)), power)
    clear = clear_air_power_dbm(first)
    rain = None if clear is None else rain_loss_of(clear[:, r, c], power)
    local, one = composed_prior_spread(excess, site_distance_m(first, (r, c)), rain)
    dev = np.hypot(_less(local, SITE_DB), one)
    return _outage_of(power, dev, SITE_DB, first.scenario.noise_power_dbm, min_db, draws, seed)


def flight_outage_among_levels(
    maps: Sequence[RadioMap],
    path_m: npt.ArrayLike,
    levels: npt.ArrayLike,
    min_db: float,
    *,
    draws: int = 4096,
    seed: int = 0,
) -> np.ndarray:
    """The outage probability of each move of a flight among flight levels.

    The move ending at ``path_m[k]`` on level ``levels[k]`` is read on that level's map with its
    spreads ([`outage_probability()`][rainuav.radio.measured.outage.outage_probability], one
    sample's outage). Each level is drawn on its own, so a physics map's site error is drawn
    once a level, not once a flight: the expected share is the same either way, and the spread
    between [`path_outage()`][rainuav.radio.measured.outage.path_outage]'s bounds still holds.

    Args:
        maps: Each level's map, lowest first.
        path_m: Where each move ends, (N, 2), m.
        levels: The level each move ends on, (N,).
        min_db: The SINR threshold, dB.
        draws: Draws per move (1-1 000 000).
        seed: The draws' seed.

    Returns:
        The outage probability at each move, (N,).

    Raises:
        InvalidInputError: ``draws`` out of its range, or a level with no map.
    """
    from rainuav._sampling import pixel_index

    path = np.asarray(path_m, dtype=float).reshape(-1, 2)
    lv = np.asarray(levels, dtype=np.int64).reshape(-1)
    if lv.size and (lv.min() < 0 or lv.max() >= len(maps)):
        raise InvalidInputError(f"levels must lie within 0..{len(maps) - 1} (the maps given)")
    out = np.zeros(len(path))
    for k in np.unique(lv):
        on = lv == k
        rm = maps[int(k)]
        r, c = pixel_index(rm.sinr_db.shape, rm.extent_m, path[on, 0], path[on, 1])
        out[on] = outage_probability(rm, min_db, seed=seed, draws=draws, pixels=(r, c))
    return out


def outage_probability(
    rm: RadioMap,
    min_db: float,
    seed: int = 0,
    draws: int = DRAWS,
    pixels: npt.ArrayLike | None = None,
    sample: bool = True,
) -> np.ndarray:
    """The probability that the SINR is below a threshold, at every pixel of a map.

    Every cell's power is drawn from the map's two spreads (module docstring; a physics map's
    site error drawn once for every cell), and the SINR of each draw compared with ``min_db``.

    Args:
        rm: The map: a corrected one with its own spreads, or a physics map (its prior's).
        min_db: The SINR threshold, dB.
        seed: The draws' seed.
        draws: Draws per pixel (1-1 000 000).
        pixels: ``(rows, columns)`` to draw at alone; default every pixel.
        sample: One sample's outage (both spreads); False: the local mean's (its spread alone).

    Returns:
        The probability, (H, W), or (N,) at the ``pixels``.

    Raises:
        InvalidInputError: ``draws`` out of its range.
    """
    if not 1 <= draws <= 1_000_000:
        raise InvalidInputError(f"draws must lie within 1..1000000 (got {draws})")
    rss = np.asarray(rm.rss_dbm, dtype=float)
    local, one, common = _drawn_spreads(rm, pixels)  # at the pixels asked for alone
    sd = np.hypot(local, one) if sample else local
    m = rss.shape[0]
    if pixels is None:
        mean, dev = rss.reshape(m, -1), sd.reshape(m, -1)
    else:
        mean, dev = rss[:, pixels[0], pixels[1]], sd
    out = _outage_of(mean, dev, common, rm.scenario.noise_power_dbm, min_db, draws, seed)
    return out if pixels is not None else out.reshape(rss.shape[1:])


def path_outage(prob: np.ndarray) -> dict[str, float]:
    """The outage share a path expects, and its spread between two bounds.

    A map's errors are correlated over its residual fields' length scales, so the spread of the
    share lies between that of independent pixels and that of fully correlated ones.

    Args:
        prob: The outage probability where each move ends, (N,).

    Returns:
        ``expected_outage_share`` (the mean probability), ``spread_independent``
        (``sqrt(sum p (1 - p)) / n``) and ``spread_correlated`` (``sum sqrt(p (1 - p)) / n``,
        the largest it can be).
    """
    p = np.asarray(prob, dtype=float)
    n = max(p.size, 1)
    q = p * (1 - p)
    return {
        "expected_outage_share": float(p.sum() / n),
        "spread_independent": float(np.sqrt(q.sum()) / n),
        "spread_correlated": float(np.sqrt(q).sum() / n),
    }


def _field_of(
    rm: RadioMap, cell: int
) -> tuple[float, float, float, list[tuple[float, float, float]]] | None:
    """The cell's residual field as the map's ``fit`` records it (length, amplitude and nugget:
    m, dB, dB; and a two-scale field's components: amplitude, lengths east and north, empty for
    one scale), None where it has none; a record that is not numbers is refused, naming it (a
    map handed over may carry anything in its ``fit_json``)."""
    fit = getattr(rm, "fit", None)
    rows = fit.get("residual") if isinstance(fit, dict) else None
    for f in rows if isinstance(rows, list) else []:
        if not isinstance(f, dict) or f.get("cell") != cell:
            continue
        try:
            got = tuple(float(f[k]) for k in ("length_m", "amplitude_db", "noise_db"))
            parts = [(float(c["amplitude_db"]), float(c["east_m"]), float(c["north_m"]))
                     for c in f.get("components") or []]  # fmt: skip
        except (KeyError, TypeError, ValueError) as err:
            raise InvalidInputError(f"the map's fit: residual of cell {cell} is not a field "
                                    f"record ({err})") from err  # fmt: skip
        if not (np.isfinite(got).all() and got[0] > 0 and min(got[1:]) >= 0):
            raise InvalidInputError(
                f"the map's fit: residual of cell {cell} must have a positive length_m and "
                "non-negative amplitude_db and noise_db"
            )
        if not all(np.isfinite(p).all() and p[1] > 0 and p[2] > 0 for p in parts):
            raise InvalidInputError(f"the map's fit: residual of cell {cell} has a "
                                    "component without positive lengths")  # fmt: skip
        return got[0], got[1], got[2], parts
    return None


def _along(rm: RadioMap, cell: int, xy: np.ndarray) -> np.ndarray | None:
    """The correlation of one cell's local-mean errors between the path's pixels ``xy`` (N, 2),
    besides any error shared by every pixel: a corrected map's residual field (its fitted
    Matern 3/2 over its length across the ground, or a two-scale field's two Materns each by its
    share, the field's share of the variance; the nugget's share independent), else independent
    pixels (a physics map's engine error, whose correlation is not measured; its site error is
    shared, drawn apart): None for independent pixels."""
    n = len(xy)
    f = _field_of(rm, cell)
    if f is None:
        return None
    length, amp, nug, parts = f
    amp2, nug2 = amp**2, nug**2
    share = amp2 / (amp2 + nug2) if amp2 + nug2 > 0 else 0.0
    delta = (xy[:, None, :] - xy[None, :, :]).transpose(2, 0, 1)
    matern = np.zeros((n, n))
    for a, east, north in parts or [(amp, length, length)]:
        d = np.hypot(delta[0] / east, delta[1] / north)
        matern += a**2 / max(amp2, 1e-12) * (1 + np.sqrt(3) * d) * np.exp(-np.sqrt(3) * d)
    return share * matern + (1 - share) * np.eye(n)


def path_outage_draws(
    rm: RadioMap,
    pixels: npt.ArrayLike,
    min_db: float,
    *,
    draws: int = 2000,
    seed: int = 0,
    sample: bool = True,
) -> dict[str, float]:
    """The outage share of a path, drawn whole: the plan's outage with its spread.

    Each draw gives every cell's local-mean errors correlated along the path (a corrected map's
    residual field; a physics map's site error shared by every pixel and every cell) and one
    sample's fading independent at every pixel.

    Args:
        rm: The map.
        pixels: ``(rows, columns)`` where the path's moves end.
        min_db: The SINR threshold, dB.
        draws: Draws of the whole path (10-100 000).
        seed: The draws' seed.
        sample: One sample's outage; False: the local mean's alone.

    Returns:
        ``expected_outage_share``, ``spread_along_path`` (its standard deviation over the
        draws), ``outage_share_p5`` and ``outage_share_p95``.

    Raises:
        InvalidInputError: ``draws`` out of its range.
    """
    if not 10 <= draws <= 100_000:
        raise InvalidInputError(f"draws must lie within 10..100000 (got {draws})")
    r, c = np.asarray(pixels[0]), np.asarray(pixels[1])
    rss = np.asarray(rm.rss_dbm, dtype=float)[:, r, c]
    local, one, common = _drawn_spreads(rm, (r, c))
    m, n = rss.shape
    if n == 0:  # a path of no moves
        return {"expected_outage_share": 0.0, "spread_along_path": 0.0,
                "outage_share_p5": 0.0, "outage_share_p95": 0.0}  # fmt: skip
    xy = np.column_stack([np.asarray(rm.x_m)[c], np.asarray(rm.y_m)[r]])
    rng = np.random.default_rng(seed)
    along = [_along(rm, k, xy) for k in range(m)]
    chol = [None if a is None else np.linalg.cholesky(a + 1e-9 * np.eye(n)) for a in along]
    reached = rss > RSS_FLOOR_DBM + 1.0
    share = np.empty(draws)
    step = max(1, int(4e6 // (m * n)))  # draws at a time: a long path in bounded memory
    for i in range(0, draws, step):
        b = min(step, draws - i)
        d = np.empty((b, m, n))
        for k in range(m):
            z = rng.standard_normal((b, n))
            d[:, k] = rss[k] + local[k] * (z if chol[k] is None else z @ chol[k].T)
        if common:
            d += common * rng.standard_normal((b, 1, 1))
        if sample:
            d += one[None] * rng.standard_normal((b, m, n))
        p = np.where(reached[None], 10 ** (np.minimum(d, 100.0) / 10), 0.0)
        sinr = sir_from_power(p.transpose(1, 0, 2).reshape(m, -1), rm.scenario.noise_power_dbm)[2]
        share[i : i + b] = (sinr.reshape(b, n) < min_db).mean(axis=1)
    return {
        "expected_outage_share": float(share.mean()),
        "spread_along_path": float(share.std()),
        "outage_share_p5": float(np.percentile(share, 5)),
        "outage_share_p95": float(np.percentile(share, 95)),
    }
