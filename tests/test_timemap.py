"""Radio maps in time, ray engine: every slice against a static
build of the frozen weather at its instant, the rain path integral against brute-force
quadrature, still weather, interpolation between slices and bad input."""

from __future__ import annotations

import numpy as np
import pytest
from rainuav import InvalidInputError
from rainuav.radio import build_radio_map, presets
from rainuav.radio.engines.ray_engine import rain_args
from rainuav.radio.outputs.timemap import build_radio_map_series
from rainuav.radio.scene.scenario import Area
from rainuav.radio.scene.weather import Medium, RainCell

TIMES = np.array([0.0, 100.0, 200.0, 300.0])


def _storm(resolution_m: float = 50.0, seed: int = 11):
    return presets.storm(seed=seed, area=Area(resolution_m=resolution_m), engine="ray")


@pytest.fixture(scope="module")
def series():
    return build_radio_map_series(_storm(), TIMES)


def test_every_slice_is_the_static_map_of_its_instant(series) -> None:
    # A slice traces the same rays as a static ray build of the frozen weather at its instant;
    # only the rain integral differs (a fan of lines from each site, read between lines, for
    # a line per pixel). Tolerance (the issue's): 0.05 dB at the 99th percentile of SINR and
    # of every cell's power (where it is above the floor), and at every pixel too; measured
    # 0.0007 dB at the 99th percentile, 0.001 dB at most.
    scn = _storm()
    for k, t in enumerate(TIMES):
        ref = build_radio_map(scn.replace(medium=scn.medium.at(t)), cache=False)
        d_sinr = np.abs(series.sinr_db[k] - ref.sinr_db)
        live = ref.rss_dbm > -200.0
        d_rss = np.abs(series.rss_dbm[k].astype(float) - ref.rss_dbm)[live]
        assert np.percentile(d_sinr, 99) < 0.05 and np.percentile(d_rss, 99) < 0.05, t
        assert d_sinr.max() < 0.05 and d_rss.max() < 0.05, t  # no pixel far off
        assert np.mean(series.serving_cell[k] == ref.serving_cell) > 0.999, t
    # The storm moves: the slices differ.
    assert not np.array_equal(series.sinr_db[0], series.sinr_db[-1])


def test_still_weather_gives_identical_slices() -> None:
    still = Medium(kind="cells", rain_rate_mm_h=2.0, cells=[RainCell(900, 900, 400, 80)])
    s = build_radio_map_series(_storm().replace(medium=still), [0.0, 60.0, 120.0])
    assert np.array_equal(s.sinr_db[0], s.sinr_db[2]) and np.array_equal(s.rss_dbm[0], s.rss_dbm[1])


def _rain_loss_db(scn, site, gamma_raster, origin_step) -> np.ndarray:
    """The direct ray's rain loss (dB) from ``site`` to every pixel of ``scn`` through a raster
    of gamma (dB/m), by the slicer: unit clear-air power on the direct ray only."""
    from rainuav import _core

    x, y = scn.area.centres()
    terms = np.zeros((1, y.size, x.size, 7))
    terms[..., 0] = 1.0
    terms[0, ..., 3] = _direct_length(scn, site, x[None, :], y[:, None])[1]
    slicer = _core.RaySlicer(
        terms, np.array([[site.x_m, site.y_m, site.height_m]]), np.zeros(1, np.int64), x, y,
        node_spacing_m=origin_step[1],
    )  # fmt: skip
    p = slicer.power(gamma_db_per_m=0.0, gamma_raster=gamma_raster, gamma_origin_step=origin_step)
    return -10.0 * np.log10(p[0])


def _direct_length(scn, site, x, y):
    rho = np.hypot(x - site.x_m, y - site.y_m)
    return rho, np.hypot(rho, scn.area.altitude_m - site.height_m)


def test_the_next_storm_reuses_what_no_weather_changes_bit_for_bit() -> None:
    # A storm pool's next storm over the same network: the rays' terms of the storm before are
    # found again (the same array, not traced anew) and the series equals one built from scratch
    # exactly (the terms do not depend on the weather).
    from rainuav.radio.outputs import timemap

    before, after = _storm(100.0, seed=3), _storm(100.0, seed=4)
    timemap._static.clear()
    fresh = build_radio_map_series(after, TIMES, cache=False)
    timemap._static.clear()
    build_radio_map_series(before, TIMES, cache=False)
    kept = dict(timemap._static)
    again = build_radio_map_series(after, TIMES, cache=False)
    assert len(kept) == len(timemap._static) == 1
    assert all(timemap._static[k] is v for k, v in kept.items())
    for name in ("rss_dbm", "sinr_db", "serving_cell"):
        assert np.array_equal(getattr(again, name), getattr(fresh, name)), name
    assert not np.array_equal(again.sinr_db, build_radio_map_series(before, TIMES).sinr_db)


def test_the_rain_path_integral_against_brute_force_quadrature() -> None:
    # The rain loss from a site to every pixel (the raster of the medium's gamma, 10 m nodes,
    # integrated along a fan of lines) against gamma(R(x, y)) of the exact rain field summed
    # at 1 m steps along each line, 200 random pixels, losses up to 12 dB. Tolerance 0.01 dB
    # (the issue's): the raster samples the 300 m Gaussian cell at 10 m nodes and the fan
    # reads between lines at most 10 m apart; measured at most 0.004 dB.
    cell = RainCell(1100.0, 900.0, 300.0, 120.0, vx_m_s=10.0)
    weather = Medium(kind="cells", rain_rate_mm_h=0.0, cells=[cell])
    scn = presets.uma(0.0, 28e9, engine="ray", medium=weather)
    scn = scn.replace(medium=scn.medium.at(30.0))
    args = rain_args(scn)
    site = scn.sites[0]
    got = _rain_loss_db(scn, site, args["gamma_raster"], args["gamma_origin_step"])
    x, y = scn.area.centres()
    rain = scn.medium.rain_medium(scn.freq_hz, scn.polarization)
    rng = np.random.default_rng(0)
    for i, j in zip(rng.integers(0, y.size, 200), rng.integers(0, x.size, 200), strict=True):
        rho, d1 = _direct_length(scn, site, x[j], y[i])
        s = np.linspace(0.0, 1.0, max(int(rho), 2))
        px, py = site.x_m + s * (x[j] - site.x_m), site.y_m + s * (y[i] - site.y_m)
        rates = scn.medium.cells[0].rate(px, py)
        want = float(np.trapezoid(rain.specific_attenuation(rates) / 1e3, s)) * d1
        assert abs(got[i, j] - want) < 0.01, (i, j, got[i, j], want)


def test_a_moving_gaussian_cell_against_the_closed_form() -> None:
    # gamma = k R^alpha (ITU-R P.838 at 28 GHz) through a Gaussian cell moved by 60 s at
    # 12 m/s: along a line, R^alpha is a Gaussian in the distance s, and its integral is
    # k R0^alpha exp(-alpha p^2 / r^2) r sqrt(pi / alpha) / 2 [erf((rho - s0) sqrt(alpha) / r)
    # + erf(s0 sqrt(alpha) / r)] (p: the centre's distance from the line, s0: its foot).
    # Every pixel of the map, tolerance 0.01 dB (the issue's); measured below 0.005 dB.
    from rainuav.medium import itu_p838
    from scipy.special import erf

    cell = RainCell(700.0, 1200.0, 250.0, 100.0, vx_m_s=12.0).at(60.0)
    scn = presets.uma(0.0, 28e9, engine="ray")
    k, alpha = _p838_power_law(scn.freq_hz, itu_p838)
    step = 10.0
    a = scn.area
    nx, ny = int((a.x_max_m - a.x_min_m) / step) + 1, int((a.y_max_m - a.y_min_m) / step) + 1
    xs, ys = a.x_min_m + step * np.arange(nx), a.y_min_m + step * np.arange(ny)
    raster = k * cell.rate(xs[None, :], ys[:, None]) ** alpha / 1e3
    site = scn.sites[2]
    got = _rain_loss_db(scn, site, raster, (a.x_min_m, step, a.y_min_m, step))
    x, y = a.centres()
    X, Y = np.meshgrid(x, y)
    rho, d1 = _direct_length(scn, site, X, Y)
    ux, uy = (X - site.x_m) / rho, (Y - site.y_m) / rho
    cx, cy = cell.x_m - site.x_m, cell.y_m - site.y_m
    s0 = cx * ux + cy * uy
    p2 = cx**2 + cy**2 - s0**2
    r, q = cell.radius_m, np.sqrt(alpha) / cell.radius_m
    integral = (
        k * cell.peak_rate_mm_h**alpha * np.exp(-alpha * p2 / r**2) * np.sqrt(np.pi) / (2 * q)
        * (erf((rho - s0) * q) + erf(s0 * q)) / 1e3
    )  # fmt: skip
    want = integral * d1 / rho
    assert want.max() > 5.0  # the cell matters
    np.testing.assert_allclose(got, want, rtol=0, atol=0.01)


def _p838_power_law(freq_hz: float, itu_p838) -> tuple[float, float]:
    """k and alpha of P.838 at ``freq_hz`` (horizontal): gamma at 1 mm/h is k, and the slope
    of log gamma against log R is alpha."""
    g1, g10 = (float(itu_p838(freq_hz, r, polarization="h")) for r in (1.0, 10.0))
    return g1, float(np.log10(g10 / g1))


def test_between_slices_the_powers_are_interpolated(series) -> None:
    mid = series.at(150.0)
    want = 0.5 * (series.rss_dbm[1].astype(float) + series.rss_dbm[2].astype(float))
    np.testing.assert_allclose(mid.rss_dbm, want, rtol=0, atol=1e-9)
    assert mid.scenario.medium == series.scenario.medium.at(150.0)
    exact = series.at(200.0)
    assert np.array_equal(exact.sinr_db, series.sinr_db[2])
    assert np.array_equal(series.at(-50.0).rss_dbm, series.rss_dbm[0].astype(float))


@pytest.mark.parametrize(
    ("times", "needle"),
    [([0.0, 0.0], "increasing"), ([0.0, float("nan")], "finite"), ([[0.0]], "instants")],
)
def test_bad_series_input_is_refused(times, needle) -> None:
    with pytest.raises(InvalidInputError, match=needle):
        build_radio_map_series(_storm(), times)
    with pytest.raises(InvalidInputError, match="engine 'ray' or 'hybrid'"):
        build_radio_map_series(_storm().replace(engine="pe"), [0.0])
    with pytest.raises(InvalidInputError, match="GB"):
        build_radio_map_series(_storm(10.0), np.arange(10_000.0))


def test_a_series_saves_loads_and_is_cached(series, tmp_path, monkeypatch) -> None:
    from rainuav.radio import RadioMapSeries

    path = series.save(tmp_path / "s.npz")
    back = RadioMapSeries.load(path)
    for k in ("t_s", "rss_dbm", "sinr_db", "sir_db", "serving_cell", "x_m", "y_m", "cell_site"):
        assert np.array_equal(getattr(back, k), getattr(series, k)), k
    assert back.scenario.digest() == series.scenario.digest()
    # build_radio_map(times_s=...) is the series; a second build reads the cache.
    monkeypatch.setenv("RAINUAV_CACHE_DIR", str(tmp_path / "cache"))
    scn = _storm(100.0)
    first = build_radio_map(scn, times_s=[0.0, 30.0])
    again = build_radio_map(scn, times_s=[0.0, 30.0])
    assert again.build_seconds == 0.0 and np.array_equal(again.sinr_db, first.sinr_db)
    assert build_radio_map(scn, times_s=[0.0, 40.0]).build_seconds > 0  # other instants
    # The cache entry carries its scenario's digest: a hit under that digest is the caller's
    # scenario, its TOML not parsed again (seconds for a radar weather); a file read on its
    # own is parsed and checked as before.
    from rainuav.radio.scene import scenario as scenario_module

    def no_parse(*_: object) -> None:
        raise AssertionError("the cached scenario's TOML was parsed")

    monkeypatch.setattr(scenario_module.Scenario, "from_toml_string", no_parse)
    hit = build_radio_map(scn, times_s=[0.0, 30.0])
    assert hit.build_seconds == 0.0 and hit.scenario is scn
    assert np.array_equal(hit.sinr_db, first.sinr_db)
    monkeypatch.undo()
    assert RadioMapSeries.load(path).scenario.digest() == series.scenario.digest()


def test_a_bad_series_file_is_refused_in_one_line(series, tmp_path) -> None:
    from rainuav.radio import RadioMapSeries

    good = dict(np.load(series.save(tmp_path / "s.npz")))
    for name, change, needle in [
        ("nan", {"sinr_db": np.where(good["sinr_db"] > 0, np.nan, good["sinr_db"])}, "NaN"),
        ("shape", {"rss_dbm": good["rss_dbm"][:, :2]}, "rss_dbm must be"),
        ("time", {"t_s": good["t_s"][::-1].copy()}, "increasing"),
        ("cell", {"serving_cell": good["serving_cell"] + 99}, "serving_cell must lie"),
        ("missing", {"t_s": None}, "missing"),
    ]:
        data = {**good, **change}
        data = {k: v for k, v in data.items() if v is not None}
        np.savez(tmp_path / f"{name}.npz", **data)
        with pytest.raises(InvalidInputError, match=needle):
            RadioMapSeries.load(tmp_path / f"{name}.npz")
    (tmp_path / "junk.npz").write_bytes(b"not a zip")
    with pytest.raises(InvalidInputError, match="not a readable"):
        RadioMapSeries.load(tmp_path / "junk.npz")


@pytest.mark.parametrize(
    ("duration", "step", "needle"),
    [
        (300.0, 7.0, "must divide"),
        (300.0, 0.0, "slice_s"),
        (float("nan"), 5.0, "duration_s"),
        (-10.0, 5.0, "duration_s"),
        (300.0, 400.0, "slice_s"),
        (1e6, 1e-3, "slice_s"),
    ],
)
def test_bad_durations_and_steps_are_named(duration, step, needle) -> None:
    from rainuav.radio.outputs.timemap import series_times

    with pytest.raises(InvalidInputError, match=needle):
        series_times(duration, step)
    assert np.array_equal(series_times(300.0, 5.0), np.arange(61) * 5.0)


@pytest.mark.slow
def test_the_radiomap_cli_writes_a_series_and_its_gif(tmp_path, monkeypatch, capsys) -> None:
    from PIL import Image
    from rainuav import radiomap
    from rainuav.radio import RadioMapSeries

    monkeypatch.setenv("RAINUAV_CACHE_DIR", str(tmp_path / "cache"))
    out = tmp_path / "out"
    argv = ["--scenario", "storm", "--storm-seed", "4", "--duration-s", "20", "--slice-s", "10"]
    assert radiomap.main([*argv, "--out", str(out)]) == 0
    s = RadioMapSeries.load(out / "radiomap_series.npz")
    assert np.array_equal(s.t_s, [0.0, 10.0, 20.0])
    with Image.open(out / "storm.gif") as gif:
        assert gif.n_frames == 3
    assert "3 slices" in capsys.readouterr().out
    for bad, needle in [
        (["--slice-s", "7"], "must divide"),
        (["--engine", "pe"], "ray or the hybrid"),
        (["--at-s", "5"], "--at-s"),
    ]:
        rest = [] if bad[0] == "--slice-s" else ["--slice-s", "10"]
        assert radiomap.main([*argv[:6], *rest, *bad, "--out", str(out)]) == 2
        err = capsys.readouterr().err
        assert needle in err and "Traceback" not in err and len(err.strip().splitlines()) == 1


@pytest.mark.slow
def test_the_hybrid_in_time_against_static_hybrid_builds() -> None:
    # The paper's network at 4.9 GHz, where the PE carries part of the power, under two moving
    # cells: the series marches the PE once in clear air and attenuates it like the direct
    # ray; a static hybrid build marches it through the frozen rain. Tolerance 0.05 dB (the
    # issue's) in SINR everywhere and in the power where the PE carries over half; measured
    # 0.0045 dB (PE budget cut to 0.05 for speed; at the default budget, 198 such
    # cell-pixels with up to 0.72 dB of rain loss agree to 0.0099 dB: benches/hybrid_in_time.py).
    from rainuav.radio.scene.scenario import PESettings

    cells = [RainCell(700.0, 900.0, 500.0, 150.0, vx_m_s=12.0),
             RainCell(1300.0, 1300.0, 400.0, 120.0, vy_m_s=-10.0)]  # fmt: skip
    scn = presets.paper().replace(
        area=Area(resolution_m=50.0), pe=PESettings(budget_gpoints=0.05),
        medium=Medium(kind="cells", rain_rate_mm_h=5.0, cells=cells), engine="hybrid",
    )  # fmt: skip
    series = build_radio_map(scn, times_s=[0.0, 60.0], cache=False)
    for k, t in enumerate(series.t_s):
        ref = build_radio_map(scn.replace(medium=scn.medium.at(t)), cache=False)
        pe = ref.pe_share > 0.5
        assert pe.sum() > 10  # the PE carries part of the map
        assert np.abs(series.sinr_db[k] - ref.sinr_db).max() < 0.05
        assert np.abs(series.rss_dbm[k] - ref.rss_dbm)[pe].max() < 0.05
    # Where no cell is marched (the storm at 28 GHz: every cone under 1%), the hybrid series
    # is the ray series.
    storm = _storm(100.0)
    hybrid = build_radio_map(storm.replace(engine="hybrid"), times_s=[0.0, 60.0], cache=False)
    ray = build_radio_map(storm, times_s=[0.0, 60.0], cache=False)
    assert np.array_equal(hybrid.sinr_db, ray.sinr_db)


def test_a_rate_grid_path_integral_against_brute_force_quadrature() -> None:
    # A rate grid (kind 'map', 21 x 21 over the area, smooth): the slicer's rain loss from a
    # site against gamma(R(x, y)) of the grid itself (its own bilinear reading) summed at 1 m
    # steps along each line, 200 random pixels. Tolerance 0.01 dB (the issue's): the rays read
    # gamma at 10 m nodes of the grid's rates; measured at most 0.0004 dB.
    from rainuav.radio.engines.pe_engine import rain_rate_at

    yy, xx = np.mgrid[0:21, 0:21] / 20.0
    rates = 40.0 + 35.0 * np.sin(3.0 * xx + 1.0) * np.cos(2.0 * yy) + 20.0 * xx * yy
    weather = Medium(kind="map", rate_map_mm_h=rates.tolist())
    scn = presets.uma(0.0, 28e9, engine="ray", medium=weather)
    args = rain_args(scn)
    site = scn.sites[4]
    got = _rain_loss_db(scn, site, args["gamma_raster"], args["gamma_origin_step"])
    x, y = scn.area.centres()
    rain = scn.medium.rain_medium(scn.freq_hz, scn.polarization)
    rng = np.random.default_rng(1)
    worst = 0.0
    for i, j in zip(rng.integers(0, y.size, 200), rng.integers(0, x.size, 200), strict=True):
        rho, d1 = _direct_length(scn, site, x[j], y[i])
        s = np.linspace(0.0, 1.0, max(int(rho), 2))
        px, py = site.x_m + s * (x[j] - site.x_m), site.y_m + s * (y[i] - site.y_m)
        g = rain.specific_attenuation(rain_rate_at(scn, px, py)) / 1e3
        worst = max(worst, abs(got[i, j] - float(np.trapezoid(g, s)) * d1))
    assert worst < 0.01, worst


def test_a_flights_outage_in_time_is_each_slices_own(series) -> None:
    # The outage chance of a flight through a moving weather (fly's summary.json), each move
    # read on the slice nearest its instant with the geometry of the spreads computed once,
    # against the second method: every slice's own map and its outage probability drawn there
    # (outage_probability, the prior's spreads of that map). The two draw other random numbers:
    # with 4096 draws a probability's standard error is at most 0.008; held to 0.04 a move and
    # 0.01 on the flight's mean (the share fly reports).
    from rainuav.nav.field import pixel_index
    from rainuav.radio.measured.outage import flight_outage_in_time, outage_probability

    rng = np.random.default_rng(3)
    first = series.at(float(series.t_s[0]))
    x0, x1, y0, y1 = first.extent_m
    path = rng.uniform([x0, y0], [x1, y1], size=(40, 2))
    t = np.sort(rng.uniform(0.0, TIMES[-1], size=40))
    fast = flight_outage_in_time(series, path, t, -2.0)
    slot = np.abs(t[:, None] - series.t_s[None, :]).argmin(axis=1)
    slow = np.empty(len(path))
    for k in np.unique(slot):
        m = series.at(float(series.t_s[k]))
        on = slot == k
        r, c = pixel_index(m.sinr_db.shape, m.extent_m, path[on, 0], path[on, 1])
        slow[on] = outage_probability(m, -2.0, pixels=(r, c), draws=4096)
    assert 0.02 < slow.mean() < 0.98, slow.mean()  # a case where the chance is not trivial
    assert np.max(np.abs(fast - slow)) < 0.04, np.max(np.abs(fast - slow))
    assert abs(fast.mean() - slow.mean()) < 0.01
