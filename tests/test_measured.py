"""Maps corrected by measurements (rainuav.radio.measured) against a truth the prior does not know.

The truth is the ``rain_cell`` preset (a 100 mm/h cell in 5 mm/h rain at 28 GHz) over sites
whose powers, tilts and azimuths differ from the database's by drawn amounts; the prior is the
database's sites in clear air. Logs are drawn from the truth along flight lines with 2 dB of
Gaussian noise (rainuav.radio.measured.synthetic), and the maps are checked at the pixels no
line crossed. No ground, so that the ray map is the direct ray alone: the calibration's model
(the antenna's gain toward each point and the spreading, moved by the offsets) is then exact, and
only the noise separates a fitted offset from the true one."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest
from rainuav.errors import InvalidInputError
from rainuav.radio import Area, build_radio_map, presets
from rainuav.radio.measured import correct_map, read_log, rss_from_rsrp
from rainuav.radio.measured.calibrate import calibrate
from rainuav.radio.measured.levels import prior_at
from rainuav.radio.measured.synthetic import (
    flight_line_pixels,
    perturbed_sites,
    sample_log,
    write_log,
)

NOISE_DB = 2.0


def _worlds(seed: int = 1, resolution_m: float = 25.0, rain: bool = True):
    area = Area(resolution_m=resolution_m)
    scn = presets.uma(0.0, 28e9, engine="ray", ground="none", area=area)
    sites, errors = perturbed_sites(scn.sites, seed)
    if rain:
        truth = presets.rain_cell(5.0, 28e9, engine="ray", ground="none", area=area, sites=sites)
    else:
        truth = scn.replace(sites=sites)
    return build_radio_map(scn, cache=False), build_radio_map(truth, cache=False), errors


@pytest.fixture(scope="module")
def worlds():
    return _worlds()


@pytest.fixture(scope="module")
def corrected(worlds):
    prior, truth, _ = worlds
    return correct_map(prior, sample_log(truth, 0.02, seed=5), cross_validate=False)


def _serving(rm, truth):
    ii, jj = np.indices(truth.serving_cell.shape)
    return rm[truth.serving_cell, ii, jj]


def _held(shape, share):
    held = np.ones(shape, bool)
    px = flight_line_pixels(shape, share)
    held[px[:, 0], px[:, 1]] = False
    return held


def test_rsrp_is_the_power_of_one_resource_element_of_the_band() -> None:
    """3GPP TS 36.101 table 5.6-1: 50 resource blocks (600 subcarriers) in 10 MHz, 100 in
    20 MHz, 6 in 1.4 MHz (the 90% rule gives 7 there: 0.7 dB high, stated in the docstring's
    rule; exact to 1e-9 dB for the others)."""
    assert rss_from_rsrp(-100.0, 10e6) == pytest.approx(-100.0 + 10 * math.log10(600), abs=1e-9)
    assert rss_from_rsrp(-100.0, 20e6) == pytest.approx(-100.0 + 10 * math.log10(1200), abs=1e-9)
    assert rss_from_rsrp(-100.0, 1.4e6) - (-100 + 10 * math.log10(72)) == pytest.approx(
        10 * math.log10(84 / 72), abs=1e-9
    )


def test_calibration_recovers_known_site_errors_within_their_uncertainty() -> None:
    """Each cell's fitted power, tilt and azimuth offset lies within 3 sigma of the true one
    (a 3-sigma band: with about 60 fitted values, the chance that noise alone puts one outside is
    15%... for independent values; the fixed seeds make it one draw, which passes), about 68% of
    them within one sigma (50-85%: an understated or overstated sigma moves the share past
    that), and the sigmas are small enough for the check to bite (power under 1 dB, tilt under
    1 degree)."""
    prior, truth, errors = _worlds(rain=False)
    log = sample_log(truth, 0.1, noise_db=NOISE_DB, seed=3)
    fits = calibrate(prior.scenario, log, prior_at(prior, log),
                     ("power_db", "tilt_deg", "azimuth_deg"))  # fmt: skip
    z = []
    for f in fits:
        if f.points < 100:  # a cell seen at few points: its sigma is wide, nothing to bite on
            continue
        for p, v in f.offsets.items():
            z.append((v - errors[f.cell][p]) / f.std[p])
            assert abs(z[-1]) <= 3, (f.cell, p, v, errors[f.cell][p], f.std[p])
        assert f.std["power_db"] < 1.0 and f.std["tilt_deg"] < 1.0
        assert f.rmse_after_db < 1.3 * NOISE_DB
    assert len(z) >= 45
    # The sigmas are neither too wide nor too narrow: about 68% of the errors within one.
    assert 0.5 <= float(np.mean(np.abs(z) <= 1)) <= 0.85


@pytest.mark.slow
def test_the_corrected_map_converges_to_the_truth_as_points_are_added(worlds) -> None:
    """At the pixels no flight line crossed, the serving cell's median absolute error falls as
    the log covers 0.5, 2 and 10% of the pixels, and where the log is dense (10%) it is within
    the measurement noise (2 dB), and within 3 dB where the prior was more than 8 dB off."""
    prior, truth, _ = worlds
    e0 = np.abs(_serving(prior.rss_dbm, truth) - _serving(truth.rss_dbm, truth))
    errs = []
    for share in (0.005, 0.02, 0.1):
        log = sample_log(truth, share, noise_db=NOISE_DB, seed=7)
        cm = correct_map(prior, log, cross_validate=False)
        e = np.abs(_serving(cm.rss_dbm, truth) - _serving(truth.rss_dbm, truth))
        held = _held(truth.sinr_db.shape, share)
        errs.append(float(np.median(e[held])))
    assert errs[0] <= float(np.median(e0)) and errs[0] > errs[1] > errs[2], errs
    assert errs[2] < NOISE_DB
    big = held & (e0 > 8)
    assert big.sum() > 100 and float(np.median(e[big])) < 3.0


@pytest.mark.slow
def test_the_standard_deviation_is_calibrated(worlds) -> None:
    """About 68% of the held-out pixels' errors lie within one standard deviation: between 50
    and 85% (a deviation that is a few tens of percent off moves the share by more than that:
    0.7 sigma covers 52%, 1.4 sigma 84%); and the cross-validated share (held-out rows, noise
    included) is in the same band."""
    prior, truth, _ = worlds
    log = sample_log(truth, 0.05, noise_db=NOISE_DB, seed=11)
    cm = correct_map(prior, log)
    e = np.abs(_serving(cm.rss_dbm, truth) - _serving(truth.rss_dbm, truth))
    sd = _serving(cm.rss_std_db, truth)
    held = _held(truth.sinr_db.shape, 0.05)
    share = float(np.mean(e[held] <= sd[held]))
    assert 0.5 <= share <= 0.85, share
    cv = cm.fit["cross_validation"]["stretch"]
    assert 0.45 <= cv["corrected"]["samples"]["within_one_sigma"] <= 0.85, cv["corrected"]
    assert cv["corrected"]["samples"]["rmse_db"] < cv["prior"]["samples"]["rmse_db"]


def test_a_corrected_map_round_trips_and_keeps_its_prior(worlds, corrected, tmp_path) -> None:
    """The .npz keeps the corrected power, its prior, the deviation and the fit, bit for bit;
    SINR is recomputed from the corrected powers; a corrected map is not corrected twice."""
    from rainuav.radio import RadioMap

    prior, truth, _ = worlds
    cm = corrected
    assert np.array_equal(cm.prior_rss_dbm, prior.rss_dbm)
    assert not np.array_equal(cm.sinr_db, prior.sinr_db)
    back = RadioMap.load(cm.save(tmp_path / "m.npz"))
    for k in ("rss_dbm", "prior_rss_dbm", "rss_std_db", "sinr_db", "serving_cell"):
        assert np.array_equal(getattr(back, k), getattr(cm, k)), k
    assert back.fit == cm.fit
    assert RadioMap.load(prior.save(tmp_path / "p.npz")).rss_std_db is None
    with pytest.raises(InvalidInputError, match="already corrected"):
        correct_map(cm, sample_log(truth, 0.02, seed=5))


def _write(path, header, rows):
    path.write_text(header + "\n" + "\n".join(rows) + "\n")
    return path


def test_bad_rows_are_counted_and_skipped(worlds, tmp_path) -> None:
    prior, _, _ = worlds
    scn = prior.scenario
    rows = [
        "100,100,100,0,-90",  # good
        "100,100,100,0,-90",  # duplicate
        "nan,100,100,0,-90",  # missing
        "5000,100,100,0,-90",  # off the area
        "100,100,100,99,-90",  # unknown cell
        "100,100,100,1,-10",  # RSRP out of range
        "200,300,100,2,-95",  # good
    ]
    tail = [0, 0, 2, 3, 4, 5, 6]  # the duplicate row stays a duplicate
    rows = [r + f",{k},2026-11-27T10:00:{k:02d}Z" for k, r in zip(tail, rows, strict=True)]
    p = _write(tmp_path / "log.csv", "X (m),y_m,Altitude,Cell,RSRP (dBm),SINR,Timestamp", rows)
    log = read_log(p, scn)
    assert log.sinr_db.tolist() == [0.0, 6.0] and log.time_s.tolist() == [0.0, 6.0]
    assert len(log) == 2 and log.rows == 7
    assert sorted(log.skipped.values()) == [1, 1, 1, 1, 1]
    assert log.rss_dbm[0] == pytest.approx(rss_from_rsrp(-90.0, scn.bandwidth_hz))
    assert "2 of 7 rows used" in log.summary()
    # short rows are short, not duplicates of each other; heights below the ground or beyond
    # 3 000 m are the log's alt_m, not the map's altitude
    more = [*rows, "100,100", "100,100", "150,150,-45,0,-90,0,x", "150,150,1e6,0,-90,0,x"]
    log = read_log(_write(tmp_path / "log2.csv", "x_m,y_m,alt_m,cell,rsrp_dbm,sinr,time", more),
                   scn)  # fmt: skip
    assert log.skipped["short rows (fewer fields than the header)"] == 2
    assert log.skipped["alt_m outside 0..3000 m above the ground"] == 2 and len(log) == 2


def test_a_log_with_no_usable_row_or_of_another_place_is_refused(worlds, tmp_path) -> None:
    from rainuav.radio.scene.scenario import Origin

    prior, _, _ = worlds
    scn = prior.scenario.replace(origin=Origin(lat_deg=47.0, lon_deg=8.0))
    far = _write(tmp_path / "far.csv", "lat,lon,alt_m,cell,rsrp_dbm",
                 ["48.1,11.5,100,0,-90", "48.1,11.6,100,1,-91"])  # fmt: skip
    with pytest.raises(InvalidInputError, match=r"no usable row of 2 .*off the area.*km from"):
        read_log(far, scn)
    with pytest.raises(InvalidInputError, match="missing column"):
        read_log(_write(tmp_path / "h.csv", "lat,lon,cell,rsrp_dbm", ["47,8,0,-90"]), scn)
    with pytest.raises(InvalidInputError, match="no data row"):
        read_log(_write(tmp_path / "e.csv", "x_m,y_m,alt_m,cell,rss_dbm", []), scn)
    with pytest.raises(InvalidInputError, match="cannot be read"):
        read_log(tmp_path / "none.csv", scn)


@pytest.mark.slow
def test_a_long_log_is_refused_and_many_bins_are_thinned(worlds, tmp_path, monkeypatch) -> None:
    """A log over MAX_ROWS is refused in one line (checked with the limit lowered: a real one
    is 2 million rows); a cell with more bins than MAX_POINTS is fitted on coarser bins, and
    says so."""
    from rainuav.radio.measured import log as logmod
    from rainuav.radio.measured import residual

    prior, truth, _ = worlds
    log = sample_log(truth, 0.1, seed=2)
    p = write_log(log, tmp_path / "log.csv")
    monkeypatch.setattr(logmod, "MAX_ROWS", 100)
    with pytest.raises(InvalidInputError, match="more than 100 rows"):
        read_log(p, prior.scenario)
    monkeypatch.setattr(residual, "MAX_POINTS", 50)
    cm = correct_map(prior, log, cross_validate=False)
    assert all(f["bins"] <= 50 for f in cm.fit["residual"])
    assert max(f["bin_m"] for f in cm.fit["residual"]) > prior.scenario.area.resolution_m


@pytest.mark.slow
def test_radiomap_corrects_a_map_by_a_log(worlds, tmp_path) -> None:
    """``python -m rainuav.radiomap --measurements LOG`` writes the corrected map, its prior, the
    deviation, fit.json and the two extra figures; a bad log exits 2 in one line."""
    import json

    from rainuav.radio import RadioMap
    from rainuav.radiomap import main

    prior, truth, _ = worlds
    cfg = prior.scenario.to_toml(tmp_path / "scn.toml")
    logp = write_log(sample_log(truth, 0.02, seed=4), tmp_path / "log.csv")
    out = tmp_path / "out"
    assert main(["--config", str(cfg), "--measurements", str(logp), "--out", str(out),
                 "--no-cache", "--calibrate", "power_db,tilt_deg"]) == 0  # fmt: skip
    rm = RadioMap.load(out / "radiomap.npz")
    assert rm.rss_std_db is not None and rm.prior_rss_dbm is not None
    fit = json.loads((out / "fit.json").read_text())
    assert {k for f in fit["calibration"] for k in f["offsets"]} <= {"power_db", "tilt_deg"}
    assert (out / "rss_std.png").stat().st_size > 0 and (out / "correction.png").exists()
    assert rm.rss_sample_std_db is not None and (out / "rss_sample_std.png").exists()
    bad = _write(tmp_path / "bad.csv", "x_m,y_m,alt_m,cell,rss_dbm", ["1e9,0,100,0,-60"])
    assert main(["--config", str(cfg), "--measurements", str(bad),
                 "--out", str(tmp_path / "o2")]) == 2  # fmt: skip
    assert main(["--config", str(cfg), "--measurements", str(logp), "--calibrate", "gain",
                 "--out", str(tmp_path / "o3")]) == 2  # fmt: skip
    assert not (tmp_path / "o2" / "radiomap.npz").exists()


def test_a_corrected_map_carries_its_deviation_in_the_geotiff(corrected, tmp_path) -> None:
    """Bands 5 and 6: the serving cell's local-mean and one-sample spreads, as the map holds
    them (float32), and both round-trip through the .npz."""
    rasterio = pytest.importorskip("rasterio")
    from rainuav.radio.outputs.maptiff import write_map_geotiff
    from rainuav.radio.scene.scenario import Origin

    scn = corrected.scenario.replace(origin=Origin(47.0, 8.0))
    cm = dataclasses.replace(corrected, scenario=scn)
    with rasterio.open(write_map_geotiff(cm, tmp_path / "m.tif")) as src:
        assert src.count == 6 and src.descriptions[4] == "rss_serving_std_db"
        assert src.descriptions[5] == "rss_serving_sample_std_db"
        band, one = src.read(5)[::-1], src.read(6)[::-1]
    assert np.allclose(band, _serving(cm.rss_std_db, cm).astype(np.float32))
    assert np.allclose(one, _serving(cm.rss_sample_std_db, cm).astype(np.float32))
    back = type(cm).load(cm.save(tmp_path / "m.npz"))
    assert np.array_equal(back.rss_sample_std_db, cm.rss_sample_std_db)


@pytest.mark.slow
def test_a_log_at_several_heights_reads_the_prior_at_each(worlds) -> None:
    """Rows flown at 60 m read the prior from a map built at 60 m (bilinear there; exact at
    pixel centres), rows at 65 m halfway between the 60 and 70 m maps (linear in height, the
    documented rule), and the residual field varies in height."""
    import dataclasses as dc

    from rainuav.radio.outputs.levelmaps import level_scenario

    prior, truth, _ = worlds
    scn = prior.scenario
    at60 = build_radio_map(level_scenario(scn, 60.0), cache=False)
    at70 = build_radio_map(level_scenario(scn, 70.0), cache=False)
    low = sample_log(at60, 0.05, seed=1)
    low = dc.replace(low, alt_m=np.full(len(low), 60.0), z_m=np.full(len(low), 60.0))
    p60 = prior_at(prior, low)
    ii = np.searchsorted(at60.y_m, low.y_m)
    jj = np.searchsorted(at60.x_m, low.x_m)
    assert np.allclose(p60, at60.rss_dbm[low.cell, ii, jj], atol=1e-9)
    mid = dc.replace(low, alt_m=np.full(len(low), 65.0), z_m=np.full(len(low), 65.0))
    want = 0.5 * (at60.rss_dbm[low.cell, ii, jj] + at70.rss_dbm[low.cell, ii, jj])
    assert np.allclose(prior_at(prior, mid), want, atol=1e-9)
    both = sample_log(truth, 0.05, seed=2)
    both = dc.replace(both, alt_m=np.where(np.arange(len(both)) % 2, 100.0, 60.0))
    both = dc.replace(both, z_m=both.alt_m)
    cm = correct_map(prior, both, cross_validate=False)
    assert any(f["height_length_m"] is not None for f in cm.fit["residual"])


@pytest.mark.slow
def test_the_guides_worked_example_finds_the_wrong_cells(tmp_path) -> None:
    """docs/measurements_example.py as the page "Maps from measurements" runs it: the two wrong
    tilts and the wrong power are found within 3 sigma (the page prints the values)."""
    import json
    import runpy
    import sys

    argv = sys.argv
    sys.argv = ["measurements_example.py", "--out", str(tmp_path)]
    try:
        runpy.run_path(str(Path(__file__).resolve().parents[1] / "docs" /
                           "measurements_example.py"), run_name="__main__")  # fmt: skip
    finally:
        sys.argv = argv
    fit = json.loads((tmp_path / "maps" / "fit.json").read_text())
    truth = {0: {"tilt_deg": 3.0}, 7: {"tilt_deg": -2.0}, 12: {"power_db": -6.0}}
    for f in fit["calibration"]:
        if f["cell"] in truth:
            for p, v in f["offsets"].items():
                want = truth[f["cell"]].get(p, 0.0)
                assert abs(v - want) <= 3 * f["std"][p], (f["cell"], p, v, want)


@pytest.mark.slow
def test_fly_plans_on_the_corrected_map_and_reports_the_expected_outage(tmp_path) -> None:
    """``python -m rainuav.fly --measurements LOG`` at the example place: a log in latitude and
    longitude naming cells ``site_id:k``, with RSRP, from a network whose ZH-002 sectors transmit
    8 dB less than the sites file says. The fit finds the 8 dB within 1 dB (not 3 sigma: the place
    has a reflecting ground, over which the calibration's model, the direct ray's gain moved, is
    approximate; the guide says so, and the tilt and height it fits with the power then pull it
    by about 0.5 dB), the summary
    gives the plan's expected outage share with its spread (the correlated bound at least the
    independent one), and fit.json is written."""
    import json

    from rainuav.fly import main
    from rainuav.radio.measured.log import rss_from_rsrp
    from rainuav.radio.scene.sites import cell_names
    from rainuav.world.place import place_scenario

    root = Path(__file__).resolve().parents[1]
    sites, start, goal = root / "examples" / "sites.csv", "47.3660,8.5380", "47.3800,8.5560"
    place = place_scenario(sites, (47.3660, 8.5380), (47.3800, 8.5560))
    scn = place.scenario
    names = cell_names(place.sites)
    real = [dataclasses.replace(s, cells=[dataclasses.replace(c, tx_power_dbm=c.tx_power_dbm - 8)
                                          for c in s.cells]) if i == 1 else s
            for i, s in enumerate(scn.sites)]  # fmt: skip
    truth = build_radio_map(scn.replace(sites=real))
    log = sample_log(truth, 0.02, cells=3, seed=1)
    lat, lon = place.georef.to_latlon(log.x_m, log.y_m)
    shift = float(rss_from_rsrp(0.0, scn.bandwidth_hz))
    rows = [
        f"{a:.7f},{b:.7f},{h:.1f},{names[c]},{v - shift:.2f}"
        for a, b, h, c, v in zip(lat, lon, log.alt_m, log.cell, log.rss_dbm, strict=True)
    ]
    logp = _write(tmp_path / "log.csv", "Latitude,Longitude,Altitude,Cell,RSRP (dBm)", rows)
    out = tmp_path / "fly"
    assert main(["--sites", str(sites), "--start", start, "--goal", goal, "--measurements",
                 str(logp), "--out", str(out)]) == 0  # fmt: skip
    summary = json.loads((out / "summary.json").read_text())
    m = summary["measurements"]
    assert 0.0 <= m["expected_outage_share"] <= 1.0
    assert m["spread_correlated"] >= m["spread_independent"] >= 0.0
    along = summary["outage_chance"]["along_path"]
    assert 0.0 <= along["outage_share_p5"] <= along["outage_share_p95"] <= 1.0
    assert along["spread_along_path"] >= 0.0
    fit = json.loads((out / "fit.json").read_text())
    zh2 = [f for f in fit["calibration"] if names[f["cell"]].startswith("ZH-002") and f["offsets"]]
    assert zh2
    for f in zh2:
        assert abs(f["offsets"]["power_db"] + 8) <= 1.0, f


@pytest.mark.slow
def test_outage_probability_by_drawing(corrected) -> None:
    """P(SINR < threshold) by 1 024 draws a pixel against two independent references: where
    one cell alone reaches and the noise is all else, the SINR is the cell's power minus the noise,
    Gaussian, and P is Phi((threshold - SINR) / sigma) exactly; on the corrected map, against 8 192
    draws with another seed; at 400 pixels. Tolerances from 1 024 draws' standard error (at most
    0.016): a mean absolute difference under 0.015 (0.8 standard errors is its expectation at
    worst) and none over 0.08 (5 standard errors: the largest of 400 pixels may reach 3.5). The
    whole map's probabilities have its shape and lie in [0, 1]."""
    from rainuav.radio.measured import outage_probability
    from scipy.stats import norm

    cm = corrected
    one = dataclasses.replace(
        cm, rss_dbm=np.where(np.arange(len(cm.rss_dbm))[:, None, None] == 0, cm.rss_dbm, -250.0),
        serving_cell=np.zeros_like(cm.serving_cell),
    )  # fmt: skip
    snr = one.rss_dbm[0] - cm.scenario.noise_power_dbm
    one.sinr_db = snr
    rng = np.random.default_rng(5)
    h, w = cm.sinr_db.shape
    r, c = np.unravel_index(rng.choice(h * w, 400, replace=False), (h, w))
    thr = float(np.median(snr))
    want = norm.cdf((thr - snr[r, c]) / one.rss_std_db[0][r, c])
    diff = np.abs(outage_probability(one, thr, draws=1024, pixels=(r, c)) - want)
    assert diff.mean() < 0.015 and diff.max() < 0.08, (diff.mean(), diff.max())
    thr = float(np.median(cm.sinr_db))
    p = outage_probability(cm, thr, draws=1024, pixels=(r, c))
    ref = outage_probability(cm, thr, seed=99, draws=8192, pixels=(r, c))
    diff = np.abs(ref - p)
    assert diff.mean() < 0.015 and diff.max() < 0.08, (diff.mean(), diff.max())
    whole = outage_probability(cm, thr, draws=16)
    assert whole.shape == cm.sinr_db.shape and 0.0 <= whole.min() <= whole.max() <= 1.0


@pytest.mark.slow
def test_a_world_of_a_corrected_map_flies_the_chance_of_outage(corrected, worlds, tmp_path) -> None:
    """``world_from(map, task)`` with the ``"chance"`` reward puts the corrected map's outage
    probabilities in the field; the environment's move then earns ``-1 - mu P`` at its end (P
    read bilinearly, as the map), and the exact plan's return is what the environment pays
    flying it (to 1e-9). The map's signal with every cell's power and its spreads
    (``with_cell_powers``), saved as ``signal.npz`` and read back, flies it as the map does
    (the same probabilities to the last bit, the same plan); a signal without them is refused
    in one line. A physics map flies it with its prior's spreads (wider than the corrected
    map's, so more pixels are uncertain)."""
    from rainuav.nav import planner
    from rainuav.nav.task import NavConfig
    from rainuav.radio.measured import outage_probability
    from rainuav.world import world_from

    task = NavConfig(goal_m=(1400.0, 1600.0), reward="chance", mu=2.0, max_steps=400)
    world = world_from(corrected, task)
    thr = world.task.min_db
    assert np.array_equal(world.field.outage_p, outage_probability(corrected, thr))
    env = world.env()
    p = planner.optimal(env, np.array([312.5, 412.5]))
    env.reset(options={"start_m": [312.5, 412.5]})
    total = 0.0
    for a in p.actions:
        _, r, term, _, _ = env.step(int(a))
        total += r
    assert term and total == pytest.approx(p.return_, abs=1e-9)
    env.reset(options={"start_m": [312.5, 412.5]})
    r = env.step(0)[1]
    assert r == pytest.approx(-1 - 2.0 * float(world.field.chance(322.5, 412.5)), abs=1e-12)
    from rainuav.radio.measured.signalrisk import signal_outage_probability, with_cell_powers
    from rainuav.signals import Signal

    sig = Signal.load(with_cell_powers(corrected).save(tmp_path / "signal.npz"))
    on_signal = world_from(sig, dataclasses.replace(task, min_db=thr))
    assert np.array_equal(on_signal.field.outage_p, world.field.outage_p)
    q = planner.optimal(on_signal.env(), np.array([312.5, 412.5]))
    assert q.return_ == pytest.approx(p.return_, abs=1e-12)
    np.testing.assert_array_equal(q.actions, p.actions)
    assert np.array_equal(signal_outage_probability(sig, thr, draws=16)[0, 0, 0],
                          outage_probability(corrected, thr, draws=16))  # fmt: skip
    with pytest.raises(InvalidInputError, match="carries its cells' powers"):
        world_from(corrected.as_signal("sinr"), dataclasses.replace(task, min_db=thr))
    physics = world_from(worlds[0], task)
    assert np.array_equal(physics.field.outage_p, outage_probability(worlds[0], thr))
    unsure = lambda q: float(np.mean((q > 0.05) & (q < 0.95)))  # noqa: E731
    assert unsure(physics.field.outage_p) > unsure(world.field.outage_p)


def test_a_two_scale_correction_maps_both_spreads_and_records_its_components(worlds) -> None:
    """``correct_map(..., kernel="two-scale")`` on the ``uma`` worlds (a log of 2% of the pixels,
    two cells a pixel): every field is two-scale with two components (long first), the map's
    local-mean spread is finite and positive wherever the cell reaches, and the corrected map is
    closer to the truth than the prior at the pixels no line crossed, where the prior is more
    than 8 dB off (median |error|, the serving cell)."""
    prior, truth, _ = worlds
    log = sample_log(truth, 0.02, cells=2, seed=5)
    cm = correct_map(prior, log, cross_validate=False, kernel="two-scale")
    assert cm.fit["residual_kernel"] == "two-scale"
    for f in cm.fit["residual"]:
        assert f["kernel"] == "two-scale" and len(f["components"]) == 2, f
        a, b = f["components"]
        assert max(a["east_m"], a["north_m"]) >= max(b["east_m"], b["north_m"]), f
    reached = prior.rss_dbm > -200.0
    std = np.asarray(cm.rss_std_db)
    assert np.isfinite(std[reached]).all() and (std[reached] > 0).all()
    held = _held(truth.serving_cell.shape, 0.02)
    off = held & (np.abs(_serving(prior.rss_dbm, truth) - _serving(truth.rss_dbm, truth)) > 8.0)
    before = np.median(np.abs(_serving(prior.rss_dbm, truth) - _serving(truth.rss_dbm, truth))[off])
    after = np.median(np.abs(_serving(cm.rss_dbm, truth) - _serving(truth.rss_dbm, truth))[off])
    assert off.sum() > 100 and after < before, (after, before, off.sum())


def test_an_auto_correction_chooses_each_cells_kernel_and_chooses_again_in_a_fold(worlds) -> None:
    """``correct_map(..., kernel="auto")`` (a log of 1% of the pixels, two cells a pixel): each
    field's kernel is the candidate of the higher held-out density, both recorded in
    ``fit.json``; a cross-validation fold (``fit_correction(..., like=...)`` on half the rows)
    scores both candidates again on its own rows, with the whole log's hyperparameters."""
    from rainuav.radio.measured.fitting import _take, fit_correction

    prior, truth, _ = worlds
    log = sample_log(truth, 0.01, cells=2, seed=6)
    cm = correct_map(prior, log, cross_validate=False, kernel="auto")
    assert cm.fit["residual_kernel"] == "auto"
    for f in cm.fit["residual"]:
        s = f["kernel_scores"]
        assert set(s) == {"one-scale", "two-scale"} and all(np.isfinite(list(s.values()))), f
        assert f["kernel"] == max(s, key=s.get), f
    p = prior_at(prior, log, 10.0)
    whole = fit_correction(prior, log, p, kernel="auto")
    half = np.arange(len(log)) % 2 == 0
    fold = fit_correction(prior, _take(log, half), p[half], like=whole)
    for c, f in fold.fields.items():
        w = whole.fields[c]
        assert f.candidates is not None and set(f.candidates) == set(w.candidates or {}), c
        assert f.kernel_scores != w.kernel_scores, c
        for k, cand in f.candidates.items():
            assert cand.gp.kernel_ == w.candidates[k].gp.kernel_, (c, k)
