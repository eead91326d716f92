"""The predictive distribution of a map: its two spreads (the local mean's and one sample's), the
prior's by mechanism, and the held-out scores, against references the code does not share.

- The Gaussian CRPS against ``properscoring.crps_gaussian`` (an independent package) and, for a
  point forecast, the absolute error.
- The fading spreads against Rayleigh's exact value and a Ricean one computed by quadrature.
- The correction on a truth with a stated fading model: the truth is a physics map whose every
  cell's power is moved by a smooth field the prior does not know; a log logs several samples a
  pixel, each with log-normal fading of a known spread. The fitted sample spread is that spread,
  and the held-out coverage at one and two sigma is a Gaussian's within its sampling error.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from rainuav.radio import Area, build_radio_map, presets
from rainuav.radio.measured import correct_map
from rainuav.radio.measured.heldout import designs
from rainuav.radio.measured.outage import map_spreads, outage_probability
from rainuav.radio.measured.prior import (
    MEASURED,
    SITE_DB,
    SPREADS,
    excess_loss_db,
    fading_std_db,
    measured_spreads,
    mechanism_of,
    prior_spread,
    site_distance_m,
    spreads_of,
)
from rainuav.radio.measured.scores import COVERAGE_GAUSSIAN, crps_gaussian, score
from rainuav.radio.measured.synthetic import sample_log

FADING_DB = 4.0
"""The truth's log-normal fading, dB."""


def test_crps_matches_properscoring_and_is_the_absolute_error_of_a_point() -> None:
    """Tolerance 1e-9 (the same closed form, computed independently)."""
    properscoring = pytest.importorskip("properscoring")
    rng = np.random.default_rng(0)
    y, mu, s = rng.normal(0, 5, 500), rng.normal(0, 5, 500), rng.uniform(0.1, 8, 500)
    assert np.allclose(crps_gaussian(y, mu, s), properscoring.crps_gaussian(y, mu, s), atol=1e-9)
    assert np.allclose(crps_gaussian(y, mu, 0.0), np.abs(y - mu), atol=1e-12)


def test_a_calibrated_gaussian_scores_its_own_coverage() -> None:
    """Errors drawn from N(0, 3^2) scored with sigma 3: coverage within 4 standard errors of
    68.3% and 95.4% (20 000 draws: 0.33% and 0.15%), RMSE within 2% of 3, bias within 0.1 dB."""
    e = np.random.default_rng(1).normal(0, 3.0, 20_000)
    s = score(e, 3.0)
    assert abs(s["within_one_sigma"] - COVERAGE_GAUSSIAN[0]) < 4 * 0.0033
    assert abs(s["within_two_sigma"] - COVERAGE_GAUSSIAN[1]) < 4 * 0.0015
    assert s["rmse_db"] == pytest.approx(3.0, rel=0.02) and abs(s["bias_db"]) < 0.1
    assert s["points"] == 20_000 and score([np.nan], [1.0])["points"] == 0


def test_fading_spreads_match_rayleigh_and_ricean_references() -> None:
    """Rayleigh: 10/ln 10 * pi/sqrt 6 = 5.570 dB exactly (within 0.03 dB, the draws' error).
    Ricean K = 7 dB: the standard deviation of 10 log10 of the power by quadrature of the
    Ricean (noncentral chi-square, 2 degrees of freedom) density, within 0.03 dB. The table's
    sample spreads are these, to 0.05 dB."""
    from scipy import integrate, stats

    rayleigh = 10 / math.log(10) * math.pi / math.sqrt(6)
    assert fading_std_db(None) == pytest.approx(rayleigh, abs=0.03)
    k = 10**0.7
    pdf = stats.ncx2(df=2, nc=2 * k, scale=1 / (2 * (k + 1))).pdf

    def moment(n: int) -> float:
        return integrate.quad(lambda p: (10 * np.log10(p)) ** n * pdf(p), 1e-12, 30, limit=400)[0]

    ricean = math.sqrt(moment(2) - moment(1) ** 2)
    assert fading_std_db(7.0) == pytest.approx(ricean, abs=0.03)
    assert SPREADS["line of sight"].sample_db == pytest.approx(ricean, abs=0.05)
    assert SPREADS["deep shadow"].sample_db == pytest.approx(rayleigh, abs=0.05)


@pytest.fixture(scope="module")
def worlds():
    """The prior: ``uma`` at 28 GHz, 25 m pixels; the truth: the same map with each cell's
    power moved by a smooth field (amplitude 4 dB, a sum of four plane waves at least 1 500 m
    long)."""
    scn = presets.uma(0.0, 28e9, engine="ray", ground="none", area=Area(resolution_m=25.0))
    prior = build_radio_map(scn, cache=False)
    rng = np.random.default_rng(7)
    gx, gy = np.meshgrid(prior.x_m, prior.y_m)
    moved = prior.rss_dbm.copy()
    for c in range(len(moved)):
        f = np.zeros_like(gx)
        for _ in range(4):
            kx, ky = rng.uniform(-1, 1, 2) * 2 * np.pi / 1500
            f += np.sin(kx * gx + ky * gy + rng.uniform(0, 2 * np.pi))
        moved[c] = np.where(prior.rss_dbm[c] > -200, moved[c] + 4.0 * f / 2.0, moved[c])
    return prior, dataclasses.replace(prior, rss_dbm=moved)


def test_the_sample_spread_and_coverage_on_a_truth_of_known_fading(worlds) -> None:
    """Eight samples a pixel with 4 dB of log-normal fading on 4 flight lines: every cell's
    fitted sample spread within 4 standard errors of 4 dB (a pooled deviation of ``d`` degrees
    of freedom, the rows less the bins: ``4 / sqrt(2 d)``), the cells' pooled one within 3%
    (about 7 000 degrees of freedom: 0.8%; the prior's slope within a pixel adds a little); at
    held-out stretches,
    single samples with both spreads and local means with theirs are within one sigma
    55-80% and within two 88-99% of the time (a Gaussian's 68% and 95%: the interval allows the
    hyperparameters' error), and the corrected map beats the prior, the prior with its power
    fitted and the nearest samples on single samples' RMSE."""
    prior, truth = worlds
    log = sample_log(truth, 0.04, cells=4, noise_db=FADING_DB, seed=3, repeat=8)
    cm = correct_map(prior, log, params=("power_db",))
    for r in cm.fit["residual"]:
        dof = int(np.sum(log.cell == r["cell"])) - r["bins"]
        assert abs(r["sample_db"] - FADING_DB) < 4 * FADING_DB / math.sqrt(2 * dof), r
    assert cm.fit["unmeasured_cells_sample_std_db"] == pytest.approx(FADING_DB, rel=0.03)
    cv = cm.fit["cross_validation"]["stretch"]
    for part in ("samples", "local_means"):
        s = cv["corrected"][part]
        assert 0.55 <= s["within_one_sigma"] <= 0.80, (part, s)
        assert 0.88 <= s["within_two_sigma"] <= 0.99, (part, s)
    assert cv["corrected"]["samples"]["points"] == len(log)  # every row scored
    rmse = {k: cv[k]["samples"]["rmse_db"] for k in ("prior", "power", "knn", "corrected")}
    assert rmse["corrected"] < min(rmse["prior"], rmse["power"], rmse["knn"]), rmse
    assert cm.rss_sample_std_db is not None and cm.rss_sample_std_db.shape == cm.rss_dbm.shape


def test_held_out_designs_are_flights_or_heights_and_stretches(worlds) -> None:
    """Two flights: one left out at a time; one flight at two heights: a height at a time;
    always five stretches of each flight, contiguous in the log's order."""
    prior, truth = worlds
    a = sample_log(truth, 0.02, cells=2, seed=1, flight=0)
    b = sample_log(truth, 0.02, cells=2, seed=2, flight=1, offset=0.25)
    both = dataclasses.replace(a, **{k: np.concatenate([getattr(a, k), getattr(b, k)])
                                     for k in ("x_m", "y_m", "z_m", "alt_m", "cell", "rss_dbm",
                                               "flight")})  # fmt: skip
    d = designs(prior, both, 10.0)
    assert set(d) == {"flight", "stretch"} and set(np.unique(d["flight"])) == {0, 1}
    s = d["stretch"][both.flight == 0]
    assert np.all(np.diff(s) >= 0) and set(np.unique(s)) == set(range(5))
    hi = dataclasses.replace(a, alt_m=np.where(np.arange(len(a)) % 2 == 0, 50.0, 100.0))
    assert set(designs(prior, hi, 10.0)) == {"height", "stretch"}


def test_a_physics_map_has_its_priors_spreads_by_mechanism(worlds) -> None:
    """Without buildings or a ground the ray map is the direct ray: every reached pixel is in
    line of sight: the excess loss, free space with the antenna's gain computed apart from the
    engine, is 0 within 0.1 dB at 99.5% of the pixels (the rest lie in the pattern's deep nulls,
    where the engine's sampled pattern and the gain's floor part), and the pixels within carry
    the line-of-sight spreads; a model error adds in quadrature; the outage
    probability of a physics map uses them and falls as the SINR rises above the threshold."""
    prior, _ = worlds
    ex = excess_loss_db(prior)
    reached = np.isfinite(ex)
    assert reached.mean() > 0.9
    los = reached & (np.abs(np.nan_to_num(ex)) < 0.1)
    assert los.sum() >= 0.995 * reached.sum()
    reached = los
    local, sample = prior_spread(prior)
    dist = site_distance_m(prior)
    los_local = MEASURED["line of sight"].local_at(dist)
    assert np.allclose(local[reached], np.hypot(los_local[reached], SITE_DB))
    assert np.all(sample[reached] == MEASURED["line of sight"].sample_db)
    # the distance is the antenna's, computed apart: the site at its height above the ground
    scn = prior.scenario
    site = scn.sites[0]
    gx, gy = np.meshgrid(prior.x_m, prior.y_m)
    ref = np.sqrt((gx - site.x_m) ** 2 + (gy - site.y_m) ** 2
                  + (prior.altitude_m - site.height_m) ** 2)  # fmt: skip
    assert np.allclose(dist[0], ref, atol=1e-6)
    bare, _ = prior_spread(prior, model_db=0.0)
    wide, _ = prior_spread(prior, model_db=6.0)
    assert np.allclose(wide, np.hypot(bare, 6.0))
    published, _ = prior_spread(prior, model_db=0.0, spreads=SPREADS)
    assert np.all(published[reached] == SPREADS["line of sight"].local_db)
    assert list(mechanism_of([0.0, 10.0, 30.0, np.nan])) == [0, 1, 2, 2]
    got_local, got_sample = map_spreads(prior)
    assert np.array_equal(got_local, local) and np.array_equal(got_sample, sample)
    px = (np.array([0, 5, 17]), np.array([3, 40, 9]))  # the same values at pixels alone
    at_local, at_sample = map_spreads(prior, px)
    assert np.array_equal(at_local, local[:, px[0], px[1]])
    assert np.array_equal(at_sample, sample[:, px[0], px[1]])
    p = outage_probability(prior, 10.0, draws=64)
    assert p.shape == prior.sinr_db.shape and np.all((p >= 0) & (p <= 1))
    bands = [(prior.sinr_db >= lo) & (prior.sinr_db < lo + 5) for lo in (0.0, 5.0, 10.0)]
    means = [p[b].mean() for b in bands]
    assert all(b.sum() > 50 for b in bands) and means[0] > means[1] > means[2], means


def test_the_held_out_line_says_how_many_rows_were_scored_and_never_fails_on_none() -> None:
    """A design where no row could be scored prints n/a, not a traceback; the count of rows
    scored is in the line."""
    from rainuav.radio.measured.heldout import held_out_line

    empty = {"samples": score([], []), "local_means": score([], [])}
    cv = {"stretch": {"folds": 1, "rows": 3} | dict.fromkeys(
        ("prior", "calibrated", "corrected", "knn"), empty
    ), "left_out": "stretch"}  # fmt: skip
    line = held_out_line(cv)
    assert "(0 of 3 rows scored)" in line and "n/a" in line


def test_a_receive_gain_by_elevation_is_recovered_and_kept_apart_from_the_field(worlds) -> None:
    """A truth whose every row is seen through a UAV antenna 6 dB weaker looking down steeply
    (a linear ramp from 0 dB at the horizon to -6 dB at -90 degrees) and logs at three heights:
    the fitted gain's ramp (its value at the steepest elevation the log saw less its value at the
    shallowest) is within 1 dB of the truth's; the map carries it at every pixel (a corrected
    map with it differs from one without), and a bad choice is refused in one line."""
    from rainuav.errors import InvalidInputError
    from rainuav.radio.measured.pattern import elevation_deg

    prior, truth = worlds
    logs = [sample_log(truth, 0.04, cells=3, noise_db=1.0, seed=s, offset=o)
            for s, o in ((1, 0.2), (2, 0.5), (3, 0.8))]  # fmt: skip
    keys = ("x_m", "y_m", "z_m", "alt_m", "cell", "rss_dbm", "flight")
    log = dataclasses.replace(logs[0], **{k: np.concatenate([getattr(g, k) for g in logs])
                                          for k in keys})  # fmt: skip
    n = len(logs[0])
    alt = np.repeat([40.0, 100.0, 160.0], [n, len(logs[1]), len(logs[2])])
    log = dataclasses.replace(
        log, alt_m=alt, z_m=alt, flight=np.repeat([0, 1, 2], [n, len(logs[1]), len(logs[2])])
    )
    el = elevation_deg(prior.scenario, log.cell, log.x_m, log.y_m, log.z_m)
    log = dataclasses.replace(log, rss_dbm=log.rss_dbm + 6.0 * np.minimum(el, 0.0) / 90.0)
    flat = dataclasses.replace(prior, rss_dbm=prior.rss_dbm)
    cm = correct_map(flat, log, params=("power_db",), receive_pattern="elevation",
                     cross_validate=False, build=lambda s: flat)  # fmt: skip
    g = cm.fit["receive_pattern"]["elevation_gain"]
    k, v = np.array(g["knots_deg"]), np.array(g["gain_db"])
    lo, hi = np.percentile(el, 2), np.percentile(el, 98)
    got = np.interp(lo, k, v) - np.interp(hi, k, v)
    want = 6.0 * (min(lo, 0) - min(hi, 0)) / 90.0
    assert abs(got - want) < 1.0, (got, want)
    off = correct_map(flat, log, params=("power_db",), cross_validate=False, build=lambda s: flat)
    assert not np.allclose(off.rss_dbm, cm.rss_dbm)
    with pytest.raises(InvalidInputError, match="receive_pattern must be one of"):
        correct_map(flat, log, receive_pattern="azimuth")


def test_measured_spreads_recover_known_spreads_by_mechanism_and_distance() -> None:
    """Errors drawn Gaussian with a standard deviation known per mechanism and distance band
    (line of sight 1 dB near, 3 dB far; diffraction 4 dB; deep shadow 6 dB with no far points):
    the table measured from them gives each band's deviation within 5% (about four standard
    errors of a 68th percentile of 4 000 draws), fills the empty bands from their neighbours,
    never falls with distance, and keeps the published spread where a mechanism has no
    points."""
    rng = np.random.default_rng(3)
    n = 4000
    parts = []
    for excess, dist, sd in ((0.0, 50.0, 1.0), (0.0, 150.0, 1.0), (0.0, 300.0, 3.0),
                             (0.0, 550.0, 3.0), (0.0, 1000.0, 3.0), (10.0, 150.0, 4.0),
                             (10.0, 300.0, 4.0), (30.0, 150.0, 6.0)):  # fmt: skip
        parts.append((np.full(n, excess), np.full(n, dist), rng.normal(0.0, sd, n), sd))
    ex = np.concatenate([p[0] for p in parts])
    d = np.concatenate([p[1] for p in parts])
    e = np.concatenate([p[2] for p in parts])
    got = measured_spreads(e, ex, d)
    assert got["line of sight"].local_db == pytest.approx((1, 1, 3, 3, 3), rel=0.05)
    assert got["diffraction, reflection"].local_db == pytest.approx((4,) * 5, rel=0.05)
    assert got["deep shadow"].local_db == pytest.approx((6,) * 5, rel=0.05)
    only_los = measured_spreads(e[ex == 0], ex[ex == 0], d[ex == 0])
    assert only_los["deep shadow"] == SPREADS["deep shadow"]
    falling = measured_spreads(rng.normal(0, 1, 2 * n), np.zeros(2 * n),
                               np.r_[np.full(n, 50.0), np.full(n, 300.0)] * 1.0)  # fmt: skip
    assert falling["line of sight"].local_db[0] <= falling["line of sight"].local_db[-1]


def _smooth_field(rng: np.random.Generator, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """A smooth field of unit variance: a sum of 20 random plane waves of 150-400 m."""
    out = np.zeros(len(x))
    for _ in range(20):
        k = 2 * np.pi / rng.uniform(150, 400)
        a = rng.uniform(0, 2 * np.pi)
        out += np.cos(k * (x * np.cos(a) + y * np.sin(a)) + rng.uniform(0, 2 * np.pi))
    return out * np.sqrt(2 / 20)


def test_a_residual_whose_size_follows_the_scale_is_fitted_scaled_and_only_then() -> None:
    """A residual field 1 dB wide where the scale is 1 and 4 dB wide where it is 4 (a lit street
    and a shadow), with bin-to-bin noise of 0.3 times the scale: the scaled field's likelihood
    is the higher, it is kept,
    and far from the measurements its deviation is 4 times wider where the scale is 4 (within
    1%: the same stationary field times the scale). The same residual without the scale's
    pattern (1.5 dB everywhere) keeps the stationary field. On held-out points the scaled field
    holds 55-80% of errors within one sigma where the scale is 4 (the stationary one, its width
    set by the lit half, holds fewer), and 55-80% where it is 1."""
    from rainuav.radio.measured.residual import fit_residual

    rng = np.random.default_rng(11)
    n = 1200
    x, y = rng.uniform(0, 1000, n), rng.uniform(0, 1000, n)
    pts = np.column_stack([x, y, np.full(n, 50.0)])
    scale = np.where(x < 500, 1.0, 4.0)
    w = _smooth_field(rng, x, y)
    resid = scale * (w + rng.normal(0, 0.3, n))
    train = rng.permutation(n) < 900
    kw = {"size_m": 10.0, "step_m": 10.0, "extent_m": 1000.0, "seed": 0}
    f = fit_residual(pts[train], resid[train], scale=scale[train], **kw)
    assert f.scaled
    far = np.array([[5000.0, 5000.0, 50.0], [5000.0, 6000.0, 50.0]])
    wide = f.std(far, np.array([1.0, 4.0]))
    assert wide[1] / wide[0] == pytest.approx(4.0, rel=0.01)
    te = ~train
    e = resid[te] - f.mean(pts[te], scale[te])
    sd = f.std(pts[te], scale[te])
    shadow = scale[te] == 4.0
    got = float(np.mean(np.abs(e[shadow]) <= sd[shadow]))
    lit = float(np.mean(np.abs(e[~shadow]) <= sd[~shadow]))
    assert 0.55 <= got <= 0.80 and 0.55 <= lit <= 0.80, (got, lit)
    flat = fit_residual(pts[train], 1.5 * w[train] + rng.normal(0, 0.3, int(train.sum())),
                        scale=scale[train], **kw)  # fmt: skip
    assert not flat.scaled
    stationary = fit_residual(pts[train], resid[train], **kw)
    assert not stationary.scaled
    e0 = resid[te] - stationary.mean(pts[te])
    sd0 = stationary.std(pts[te])
    assert np.mean(np.abs(e0[shadow]) <= sd0[shadow]) < got


def test_a_map_in_rain_adds_the_spread_of_its_rain_loss(worlds) -> None:
    """The same ``uma`` map in 25 mm/h of rain: each pixel's rain loss is the clear map's power
    less the wet one's (at least 0 dB, and some pixels lose more than 8 dB at 28 GHz), its
    spread the band's of ``RAIN_SPREAD_DB`` (a loss of 3 dB: 2.36 dB), and the local mean's
    spread is the clear map's and that in quadrature (within 1e-9 dB); a map in clear air has
    no rain loss. The band table itself is checked on real links in tests/test_cml_links.py."""
    from rainuav.radio.measured.prior import RAIN_SPREAD_DB, rain_loss_db, rain_spread_db

    prior, _ = worlds
    assert rain_loss_db(prior) is None
    wet = build_radio_map(presets.with_rain(prior.scenario, 25.0), cache=False)
    loss = rain_loss_db(wet)
    assert loss is not None and loss.shape == wet.rss_dbm.shape
    reached = wet.rss_dbm > -200
    assert np.all(loss >= 0) and np.percentile(loss[reached], 99) > 8.0
    assert rain_spread_db(np.array([0.0, 0.3, 3.0, 40.0])) == pytest.approx(
        [0.0, RAIN_SPREAD_DB[0], 2.36, RAIN_SPREAD_DB[-1]]
    )
    local, _ = prior_spread(wet)
    dry, _ = spreads_of(excess_loss_db(wet), site_distance_m(wet), SITE_DB)
    assert np.allclose(local, np.hypot(dry, rain_spread_db(loss)), atol=1e-9)


def test_a_physics_maps_outage_draws_the_site_error_once_for_every_cell(worlds) -> None:
    """The outage probability of a physics map against a brute-force draw written apart: each
    cell's power its map value plus its own error (the local spread less the site error, in
    quadrature) and one site error shared by every cell, the SINR of the strongest over the
    rest and the noise: 200 000 draws at five pixels whose probability lies within 0.1-0.9,
    held within four standard errors of the two estimates together."""
    prior, _ = worlds
    p_map = outage_probability(prior, 10.0, draws=256)
    cand = np.argwhere((p_map > 0.1) & (p_map < 0.9))
    assert len(cand) >= 5
    px = tuple(cand[np.linspace(0, len(cand) - 1, 5).astype(int)].T)
    draws = 20_000
    got = outage_probability(prior, 10.0, draws=draws, pixels=px, sample=False)
    local, _ = map_spreads(prior, px)
    own = np.sqrt(local**2 - SITE_DB**2)
    rss = np.asarray(prior.rss_dbm)[:, px[0], px[1]]
    noise = 10 ** (prior.scenario.noise_power_dbm / 10)
    rng = np.random.default_rng(99)
    n = 200_000
    for j in range(5):
        reached = rss[:, j] > -200
        d = (rss[reached, j][None] + own[reached, j][None] * rng.standard_normal((n, reached.sum()))
             + SITE_DB * rng.standard_normal((n, 1)))  # fmt: skip
        p = 10 ** (np.minimum(d, 100.0) / 10)
        best = p.max(axis=1)
        sinr = 10 * np.log10(best / (p.sum(axis=1) - best + noise))
        want = float(np.mean(sinr < 10.0))
        se = np.sqrt(want * (1 - want) * (1 / draws + 1 / n))
        assert abs(got[j] - want) <= 4 * se + 1e-3, (j, got[j], want)


def test_a_paths_outage_drawn_whole_agrees_with_its_pixels_and_lies_between_the_bounds(
    worlds,
) -> None:
    """A straight path of 60 pixels across the physics map: the share of outage drawn whole
    along it (``path_outage_draws``) has the mean of its pixels' outage probabilities (within
    four standard errors of the two estimates), and its spread lies between the bounds of
    independent and fully correlated pixels (the site error shared by every pixel makes it wider
    than the independent bound); on a corrected map the residual field correlates neighbouring
    pixels (the correlation matrix is the field's share of the variance times its Matern)."""
    from rainuav.radio.measured.outage import _along, path_outage, path_outage_draws

    prior, truth = worlds
    r = np.full(60, 40)
    c = np.arange(10, 70)
    prob = outage_probability(prior, 10.0, pixels=(r, c), draws=20_000)
    got = path_outage_draws(prior, (r, c), 10.0, draws=4000)
    bounds = path_outage(prob)
    se = np.sqrt(got["spread_along_path"] ** 2 / 4000 + 0.25 / 20_000 / 60)
    assert abs(got["expected_outage_share"] - bounds["expected_outage_share"]) <= 4 * se + 1e-3
    assert bounds["spread_independent"] < got["spread_along_path"]
    assert got["spread_along_path"] <= bounds["spread_correlated"] * 1.05
    assert got["outage_share_p5"] <= got["expected_outage_share"] <= got["outage_share_p95"]
    log = sample_log(truth, 0.02, cells=3, seed=5)
    cm = correct_map(prior, log, cross_validate=False)
    f = cm.fit["residual"][0]
    xy = np.column_stack([prior.x_m[c], prior.y_m[r]])
    k = _along(cm, int(f["cell"]), xy)
    share = f["amplitude_db"] ** 2 / (f["amplitude_db"] ** 2 + f["noise_db"] ** 2)
    d = abs(xy[1, 0] - xy[0, 0]) / f["length_m"]
    want = share * (1 + np.sqrt(3) * d) * np.exp(-np.sqrt(3) * d)
    assert k[0, 0] == pytest.approx(1.0) and k[0, 1] == pytest.approx(want)
    drawn = path_outage_draws(cm, (r, c), 10.0, draws=500)
    assert 0.0 <= drawn["outage_share_p5"] <= drawn["outage_share_p95"] <= 1.0


def test_a_receive_gain_against_the_heading_is_learned_and_spreads_the_map(
    worlds, tmp_path
) -> None:
    """A log with the UAV's heading, each row's power moved by a known airframe pattern,
    ``g(phi) = 3 cos phi + 1.5 sin 2 phi`` dB of the cell's azimuth relative to the nose: the
    fitted coefficients are those within 0.3 dB (here 2.86 and 1.60 dB; the residual field and
    the ridge take a little), the held-out RMSE at held-out stretches is lower with it than
    without by more than 0.3 dB (here 4.32 against 5.01: the rows predicted with their own
    headings), and on the map, where the heading is
    not known, its root mean square (2.37 dB) joins one sample's spread in quadrature (close to
    the sample spread of the map fitted without it, whose rows' scatter took it). A heading
    column is read under its aliases and wrapped to 0..360 degrees (-90 is 270; a blank keeps
    its row, its heading unknown); asking for the gain of a log without one is refused."""
    import dataclasses

    from rainuav.errors import InvalidInputError
    from rainuav.radio.measured import read_log
    from rainuav.radio.measured.pattern import relative_azimuth_deg

    prior, truth = worlds
    log = sample_log(truth, 0.02, cells=4, seed=21, repeat=2)
    rng = np.random.default_rng(4)
    head = rng.uniform(0, 360, len(log))
    rel = np.radians(relative_azimuth_deg(prior.scenario, log.cell, log.x_m, log.y_m, head))
    g = 3.0 * np.cos(rel) + 1.5 * np.sin(2 * rel)
    flown = dataclasses.replace(log, rss_dbm=log.rss_dbm + g, heading_deg=head)
    cm = correct_map(prior, flown, receive_pattern="heading")
    got = cm.fit["receive_pattern"]["heading_gain"]
    assert got["cos_db"] == pytest.approx([3.0, 0.0], abs=0.3)
    assert got["sin_db"] == pytest.approx([0.0, 1.5], abs=0.3)
    assert got["spread_db"] == pytest.approx(np.sqrt((9 + 2.25) / 2), abs=0.2)
    off = correct_map(prior, flown)
    for design in ("stretch",):
        with_it = cm.fit["cross_validation"][design]["corrected"]["samples"]["rmse_db"]
        without = off.fit["cross_validation"][design]["corrected"]["samples"]["rmse_db"]
        assert with_it < without - 0.3, (with_it, without)
    for f in cm.fit["residual"]:  # the field's own sample spread, and the heading's
        c = f["cell"]
        assert np.allclose(cm.rss_sample_std_db[c], np.hypot(f["sample_db"], got["spread_db"]))
    # without the gain the rows' scatter took it: the two maps' sample spreads are alike
    assert abs(np.median(cm.rss_sample_std_db) - np.median(off.rss_sample_std_db)) < 0.6
    with pytest.raises(InvalidInputError, match="heading_deg"):
        correct_map(prior, log, receive_pattern="heading")
    csv = tmp_path / "h.csv"
    csv.write_text("x_m,y_m,alt_m,cell,rss_dbm,Heading (deg)\n"
                   f"{prior.x_m[3]},{prior.y_m[3]},100,0,-70,-90\n"
                   f"{prior.x_m[4]},{prior.y_m[4]},100,0,-70,\n")  # fmt: skip
    read = read_log(csv, prior.scenario)
    assert len(read) == 2 and read.heading_deg[0] == 270.0 and np.isnan(read.heading_deg[1])
