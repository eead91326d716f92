"""Radio maps against Friis, the specific attenuation, rain-cell path integrals, building
shadows and hand-computed SIR; scenario files, the cache and bad presets."""

from __future__ import annotations

import copy
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import rainuav
from rainuav import medium
from rainuav.errors import InvalidInputError
from rainuav.radio import build_radio_map, presets
from rainuav.radio.engines.pe_engine import rain_rate_at
from rainuav.radio.outputs import cache
from rainuav.radio.outputs import sinr as sinr_mod
from rainuav.radio.outputs.maps import RadioMap
from rainuav.radio.scene.scenario import (
    Area,
    Building,
    Cell,
    Medium,
    PESettings,
    RainCell,
    Scenario,
    Site,
)

C0 = 299_792_458.0


@pytest.fixture(autouse=True)
def _private_cache(tmp_path, monkeypatch):
    monkeypatch.setenv("RAINUAV_CACHE_DIR", str(tmp_path / "cache"))


def beam_line(freq_hz=4.9e9, bw=4.333, length=600.0, med=None, buildings=(), res=5.0):
    """One horizontal beam from (0, 500) at 100 m along +x, free space, flying at 100 m."""
    area = Area(
        x_min_m=0.0,
        x_max_m=length,
        y_min_m=500 - 10 * res - res / 2,
        y_max_m=500 + 10 * res + res / 2,
        altitude_m=100.0,
        resolution_m=res,
    )
    return Scenario(
        name="line",
        freq_hz=freq_hz,
        area=area,
        ground="none",
        sites=[
            Site(
                x_m=0.0,
                y_m=500.0,
                height_m=100.0,
                cells=[Cell(azimuth_deg=0.0, tilt_deg=0.0, beamwidth_deg=bw)],
            )
        ],
        medium=med or Medium(kind="clear"),
        buildings=list(buildings),
        pe=PESettings(top_margin_m=30.0),
    )


def boresight(rm):
    i = int(np.argmin(np.abs(rm.y_m - 500.0)))
    assert abs(rm.y_m[i] - 500.0) < 1e-9
    return rm.x_m, rm.rss_dbm[0, i]


def test_friis_on_boresight() -> None:
    # Far-field boresight power of a Gaussian beam: Pt + D + 20 log10(lambda / (4 pi r)) with
    # D = 4 ln2 / (sin(bh/2) sin(bv/2)) (docs/physics.md beam). zR = 4.7 m here, so beyond 100 m
    # the near-field correction is < 0.01 dB; 0.5 dB is the bar on the calibration.
    scn = beam_line()
    rm = build_radio_map(scn, cache=False)
    x, rss = boresight(rm)
    lam = C0 / scn.freq_hz
    s = math.sin(math.radians(4.333 / 2))
    d_dbi = 10 * math.log10(4 * math.log(2) / s**2)
    sel = x > 100
    friis = 46.0 + d_dbi + 20 * np.log10(lam / (4 * np.pi * x[sel]))
    err = np.abs(rss[sel] - friis)
    assert err.max() < 0.5, err.max()


@pytest.mark.slow
def test_homogeneous_rain_on_boresight() -> None:
    # Rain minus clear along boresight equals -gamma * r within 0.1 dB (28 GHz, 25 mm/h:
    # 4.8 dB/km, so up to 2.4 dB at 500 m); and rain never adds power anywhere (one beam:
    # no interference).
    kw = {"freq_hz": 28e9, "bw": 2.0, "length": 500.0}
    clear = build_radio_map(beam_line(**kw), cache=False)
    rain = build_radio_map(
        beam_line(**kw, med=Medium(kind="homogeneous", rain_rate_mm_h=25.0)), cache=False
    )
    x, rc = boresight(clear)
    _, rr = boresight(rain)
    gamma = medium.specific_attenuation(28e9, 25.0)
    sel = x > 50
    assert np.abs((rr - rc)[sel] + gamma * x[sel] / 1000).max() < 0.1
    strong = clear.rss_dbm > clear.rss_dbm.max() - 60
    assert np.all(rain.rss_dbm[strong] <= clear.rss_dbm[strong] + 1e-6)


@pytest.mark.slow
def test_rain_cell_loss_is_the_path_integral() -> None:
    # A gaussian rain cell straddling the beam at 250 m: the loss at 500 m equals the
    # integral of the specific attenuation of the local rate along the path within 5%.
    cell = RainCell(x_m=250.0, y_m=500.0, radius_m=60.0, peak_rate_mm_h=80.0)
    kw = {"freq_hz": 28e9, "bw": 2.0, "length": 500.0}
    clear = build_radio_map(beam_line(**kw), cache=False)
    rain = build_radio_map(
        beam_line(**kw, med=Medium(kind="cells", rain_rate_mm_h=0.0, cells=[cell])), cache=False
    )
    x, rc = boresight(clear)
    _, rr = boresight(rain)
    z = np.linspace(0, x[-1], 4001)
    gamma = medium.specific_attenuation(28e9, cell.rate(z, 500.0))
    want = np.trapezoid(gamma, z) / 1000
    got = rc[-1] - rr[-1]
    assert want > 1.0
    assert got == pytest.approx(want, rel=0.05)


def test_building_casts_a_shadow() -> None:
    # A 150 m tall slab across the beam at 200-220 m: behind it the power is at least 10 dB
    # below the same map without it, and before it the two agree to 1e-4 dB. Not exactly: the
    # map without it marches on the uniform-medium path (lateral window every few steps), the
    # one with it on the general step; measured 1.3e-5 dB apart (f32 rounding in another order
    # and the coarser sampling of the absorbing strips).
    slab = Building(x0_m=200.0, x1_m=220.0, y0_m=300.0, y1_m=700.0, height_m=150.0)
    free = build_radio_map(beam_line(), cache=False)
    shadow = build_radio_map(beam_line(buildings=[slab]), cache=False)
    x, rf = boresight(free)
    _, rs = boresight(shadow)
    behind = x > 300
    assert np.all(rs[behind] <= rf[behind] - 10)
    np.testing.assert_allclose(rs[x < 190], rf[x < 190], atol=1e-4)


def test_sir_by_hand() -> None:
    # Three cells, three pixels: hand-computed serving cell, SIR and SINR (docs/physics.md 5).
    p = np.array([[[1.0, 1e-3, 0.0]], [[0.5, 2e-3, 0.0]], [[0.25, 0.0, 0.0]]])
    serving, sir, sinr = sinr_mod.sir_from_power(p, noise_dbm=10 * np.log10(0.25))
    assert serving.tolist() == [[0, 1, -1]]
    assert sir[0, 0] == pytest.approx(10 * np.log10(1.0 / 0.75))
    assert sir[0, 1] == pytest.approx(10 * np.log10(2e-3 / 1e-3))
    assert sir[0, 2] == sinr_mod.SIR_FLOOR_DB
    assert sinr[0, 0] == pytest.approx(10 * np.log10(1.0 / 1.0))
    assert np.isfinite(sir).all() and np.isfinite(sinr).all()


@pytest.mark.slow
def test_mirror_symmetric_scenario_gives_mirror_symmetric_map() -> None:
    # 700 m x 400 m at 3.5 GHz: the march's grid is what is mirrored, its size is not.
    area = Area(x_min_m=0, x_max_m=700, y_min_m=0, y_max_m=400, altitude_m=100, resolution_m=20)
    sites = [
        Site(x_m=200.0, y_m=100.0, cells=[Cell(azimuth_deg=60.0, beamwidth_deg=8.0)]),
        Site(x_m=500.0, y_m=100.0, cells=[Cell(azimuth_deg=120.0, beamwidth_deg=8.0)]),
    ]
    scn = Scenario(name="mirror", area=area, sites=sites, freq_hz=3.5e9)
    rm = build_radio_map(scn, cache=False)
    a, b = rm.rss_dbm[0], rm.rss_dbm[1][:, ::-1]
    strong = (a > a.max() - 50) | (b > b.max() - 50)
    # The march grids are symmetric up to their one extra sample at -nx/2 (in the absorber):
    # 0.05 dB.
    assert np.abs(a - b)[strong].max() < 0.05
    sir = rm.sir_db
    both = strong & strong[:, ::-1]
    assert np.abs(sir - sir[:, ::-1])[both].max() < 0.1


def test_paper_preset_has_good_and_weak_regions(session_cache, monkeypatch) -> None:
    # The preset's layout in its rain, mapped by the rays: the hybrid's PE, 27 s of this
    # test with it, changes the SINR only inside the cells' cones and gave the same share
    # above 10 dB (0.114 both). The PE over the paper's own cells is checked in
    # test_engines.py (the whole area) and test_levels.py (all seven cells).
    # The map cache these tests share: the second build below must be read from it.
    monkeypatch.setenv("RAINUAV_CACHE_DIR", str(session_cache))
    scn = presets.paper(rain_rate_mm_h=25.0, engine="ray")
    rm = build_radio_map(scn, cache=True)
    cov = rm.coverage(10.0)
    assert 0.10 <= cov <= 0.95, cov
    assert rm.rss_dbm.shape == (7, 200, 200)
    assert np.isfinite(rm.sir_db).all() and np.isfinite(rm.sinr_db).all()
    # The cache returns the same map, bit for bit.
    again = build_radio_map(presets.paper(rain_rate_mm_h=25.0, engine="ray"), cache=True)
    np.testing.assert_array_equal(again.rss_dbm, rm.rss_dbm)
    assert again.build_seconds == 0.0  # from the cache


def test_save_load_round_trip_and_corrupt_cache(tmp_path: Path) -> None:
    scn = beam_line(length=200.0, res=10.0)
    rm = build_radio_map(scn, cache=True)
    path = rm.save(tmp_path / "m.npz")
    back = RadioMap.load(path)
    for k in RadioMap._ARRAYS:
        np.testing.assert_array_equal(getattr(back, k), getattr(rm, k))
        assert getattr(back, k).dtype == getattr(rm, k).dtype
    assert back.scenario == scn and back.extent_m == rm.extent_m
    # A corrupt cache entry is rebuilt, not trusted.
    entry = cache.map_path(scn.digest())
    entry.write_bytes(b"not a zip")
    rebuilt = build_radio_map(scn, cache=True)
    np.testing.assert_array_equal(rebuilt.rss_dbm, rm.rss_dbm)
    assert RadioMap.load(entry).scenario == scn
    with pytest.raises(rainuav.InvalidInputError, match="radio map"):
        RadioMap.load(tmp_path / "missing.npz")


def test_toml_round_trip(tmp_path: Path) -> None:
    for scn in (
        presets.paper(),
        presets.urban(rain_rate_mm_h=0.0),
        beam_line(med=Medium(kind="cells", cells=[RainCell(1, 2, 3, 4)])),
    ):
        path = scn.to_toml(tmp_path / f"{scn.name}.toml")
        back = Scenario.from_toml(path)
        assert back == scn
        assert back.digest() == scn.digest()


@pytest.mark.parametrize(
    ("change", "needle"),
    [
        (lambda s: s.sites.append(Site(x_m=5000.0, y_m=10.0)), "sites[7].x_m"),
        (lambda s: setattr(s.area, "altitude_m", -5.0), "area.altitude_m"),
        (lambda s: setattr(s.area, "altitude_m", 0.0), "area.altitude_m"),
        (
            lambda s: s.sites[0].cells.append(copy.deepcopy(s.sites[0].cells[0])),
            "overlaps another cell",
        ),
        (lambda s: setattr(s.sites[1], "cells", []), "sites[1].cells"),
        (lambda s: s.sites.append(Site(x_m=1000.0, y_m=1000.0)), "overlaps another site"),
        (lambda s: setattr(s.medium, "rain_rate_mm_h", -1.0), "medium.rain_rate_mm_h"),
        (lambda s: setattr(s, "freq_hz", 1e6), "freq_hz"),
        (lambda s: setattr(s.area, "x_max_m", -1.0), "area.x_max_m"),
        (lambda s: setattr(s.sites[0].cells[0], "beamwidth_deg", 0.0), "beamwidth_deg"),
        (lambda s: setattr(s.medium, "kind", "fog"), "medium.kind"),
        (lambda s: s.buildings.append(Building(990, 1010, 990, 1010, 30.0)), "inside"),
    ],
)
def test_invalid_scenarios(change, needle) -> None:
    scn = presets.paper()
    change(scn)
    with pytest.raises(ValueError, match=re_escape(needle)) as info:
        scn.check()
    assert isinstance(info.value, rainuav.InvalidInputError)


def re_escape(s: str) -> str:
    import re

    return re.escape(s)


def test_unknown_toml_field_and_budget_too_small_for_any_cone(tmp_path: Path) -> None:
    bad = tmp_path / "bad.toml"
    bad.write_text('name = "x"\nfrequency = 5e9\n')
    with pytest.raises(rainuav.InvalidInputError, match="unknown field"):
        Scenario.from_toml(bad)
    # 100 GHz, wide beams, 20 km: the march would need far more than its budget (and this
    # machine's memory: the march's own memory check is tested in test_pwe_errors). The cone
    # narrows to fit pe.budget_gpoints; a budget too small for any cone is refused by name.
    huge = presets.paper(
        freq_hz=1e11,
        area=Area(x_min_m=0, x_max_m=20000, y_min_m=0, y_max_m=20000, resolution_m=50),
        sites=[Site(x_m=100.0, y_m=100.0, cells=[Cell(azimuth_deg=45.0, beamwidth_deg=30.0)])],
        pe=PESettings(budget_gpoints=0.001),
    )
    with pytest.raises(rainuav.InvalidInputError, match=r"pe\.budget_gpoints"):
        build_radio_map(huge, cache=False)


@pytest.mark.slow
def test_cli_writes_npz_and_pngs(tmp_path: Path) -> None:
    cfg = beam_line(length=200.0, res=10.0).to_toml(tmp_path / "tiny.toml")
    out = tmp_path / "maps"
    proc = subprocess.run(
        [
            sys.executable,
            "-m",
            "rainuav.radiomap",
            "--config",
            str(cfg),
            "--rain-rate-mm-h",
            "10",
            "--out",
            str(out),
            "--no-cache",
        ],
        capture_output=True,
        text=True,
        check=True,
        env={"MPLBACKEND": "Agg", "PATH": "", "RAINUAV_CACHE_DIR": str(tmp_path / "c")},
    )
    assert "SINR median" in proc.stdout and "PE share" in proc.stdout
    rm = RadioMap.load(out / "radiomap.npz")
    assert rm.scenario.medium.rain_rate_mm_h == 10.0
    for png in ("rss.png", "sir.png", "sinr.png", "serving.png", "rss_std.png",
                "rss_sample_std.png"):  # fmt: skip
        assert (out / png).read_bytes()[:4] == b"\x89PNG"
    # A physics map says how sure it is: its prior's spreads, in the file (not a corrected map)
    # and equal to what prior_spread computes of the map (the rain's spread included).
    from rainuav.radio.measured.prior import prior_spread

    assert rm.prior_rss_dbm is None and not (out / "correction.png").exists()
    local, sample = prior_spread(rm)
    assert np.allclose(rm.rss_std_db, local) and np.allclose(rm.rss_sample_std_db, sample)


@pytest.mark.slow
def test_height_map_equals_box_building() -> None:
    # The same slab as a height map (5 m pixels over the 600 m x 105 m area) and as a box.
    slab = Building(x0_m=200.0, x1_m=220.0, y0_m=447.5, y1_m=552.5, height_m=150.0)
    box = build_radio_map(beam_line(buildings=[slab]), cache=False)
    scn = beam_line()
    h, w = scn.area.shape
    hm = np.zeros((h, w))
    hm[:, 40:44] = 150.0  # x in [200, 220)
    scn.height_map_m = hm.tolist()
    scn.check()
    mapped = build_radio_map(scn, cache=False)
    x, rb = boresight(box)
    _, rh = boresight(mapped)
    behind = x > 300
    assert np.all(
        rh[behind] <= boresight(build_radio_map(beam_line(), cache=False))[1][behind] - 10
    )
    np.testing.assert_allclose(rh[x < 190], rb[x < 190], atol=1e-6)


@pytest.mark.slow
def test_rate_map_equals_homogeneous_rain() -> None:
    # A uniform rate map is homogeneous rain: same boresight power to f32 rounding.
    kw = {"freq_hz": 28e9, "bw": 2.0, "length": 300.0}
    h, w = beam_line(**kw).area.shape
    table = np.full((h, w), 25.0).tolist()
    a = build_radio_map(
        beam_line(**kw, med=Medium(kind="homogeneous", rain_rate_mm_h=25.0)), cache=False
    )
    b = build_radio_map(beam_line(**kw, med=Medium(kind="map", rate_map_mm_h=table)), cache=False)
    _, ra = boresight(a)
    _, rb = boresight(b)
    np.testing.assert_allclose(rb, ra, atol=1e-3)
    scn = beam_line(**kw)
    scn.medium = Medium(kind="map", rate_map_mm_h=[[0.0, 10.0], [20.0, 30.0]])
    x0, x1, y0, y1 = scn.area.x_min_m, scn.area.x_max_m, scn.area.y_min_m, scn.area.y_max_m
    cx, cy = (x0 + x1) / 2, (y0 + y1) / 2
    assert rain_rate_at(scn, np.array([cx]), np.array([cy]))[0] == pytest.approx(15.0)


def test_with_rain_changes_only_the_rain() -> None:
    # --rain-rate-mm-h replaces the scenario's rain field, never its rain model, drop sizes,
    # shape, temperature or wind.
    weather = Medium(
        kind="cells",
        rain_rate_mm_h=2.0,
        cells=[RainCell(x_m=100.0, y_m=500.0, radius_m=50.0, peak_rate_mm_h=80.0)],
        model="quasi-static",
        dsd="joss-drizzle",
        shape="sphere",
        temperature_c=10.0,
        wind_speed_m_s=5.0,
        wind_model="paper",
    )
    scn = beam_line(med=weather)
    for rate, kind in ((50.0, "homogeneous"), (0.0, "clear")):
        got = presets.with_rain(scn, rate).medium
        assert (got.kind, got.rain_rate_mm_h, got.cells) == (kind, rate, [])
        for name in ("model", "dsd", "shape", "temperature_c", "wind_speed_m_s", "wind_model"):
            assert getattr(got, name) == getattr(weather, name), name
    assert scn.medium == weather  # the original is untouched


def test_the_scenarios_wind_model_reaches_the_rain_medium(tmp_path: Path) -> None:
    # A scenario's wind model is the one rainuav.medium applies (the paper's 1/cos factor
    # against drop canting, both at 5 m/s, 4.9 GHz, 50 mm/h: the same gamma to 1e-12), it
    # round-trips through TOML and changes the cache key; a model not known is refused.
    def gamma(weather: Medium) -> float:
        return float(weather.rain_medium(4.9e9, "h").specific_attenuation(50.0))

    for model in ("canting", "paper"):
        weather = Medium(kind="homogeneous", rain_rate_mm_h=50.0, wind_speed_m_s=5.0,
                         wind_model=model)  # fmt: skip
        direct = float(
            medium.RainMedium(4.9e9, wind_speed_m_s=5.0, wind_model=model).specific_attenuation(
                50.0
            )
        )
        assert gamma(weather) == pytest.approx(direct, rel=1e-12)
    canting = beam_line(med=Medium(kind="homogeneous", wind_speed_m_s=5.0))
    paper = beam_line(med=Medium(kind="homogeneous", wind_speed_m_s=5.0, wind_model="paper"))
    assert gamma(paper.medium) > gamma(canting.medium)  # the factor only grows gamma
    assert canting.digest() != paper.digest()
    back = Scenario.from_toml(paper.to_toml(tmp_path / "s.toml"))
    assert back.medium.wind_model == "paper" and back.digest() == paper.digest()
    with pytest.raises(InvalidInputError, match="wind_model"):
        beam_line(med=Medium(kind="homogeneous", wind_model="gale"))


def test_cache_key_changes_with_the_engine(monkeypatch) -> None:
    # A map cached by other engine code is not reused: the key hashes
    # the engine's fingerprint (version, Python engine sources, compiled core).
    scn = beam_line(length=200.0, res=10.0)
    first = build_radio_map(scn, cache=True)
    assert build_radio_map(scn, cache=True).build_seconds == 0.0  # a cache hit
    old_path = cache.map_path(scn.digest())
    monkeypatch.setattr(cache, "ENGINE_VERSION", cache.ENGINE_VERSION + 1)
    cache.engine_fingerprint.cache_clear()
    try:
        assert cache.map_path(scn.digest()) != old_path
        again = build_radio_map(scn, cache=True)
        assert again.build_seconds > 0.0  # rebuilt, not taken from the old entry
        np.testing.assert_array_equal(again.rss_dbm, first.rss_dbm)
    finally:
        cache.engine_fingerprint.cache_clear()
    assert cache.clear_cache() == 2  # both entries
    assert not list((cache.cache_dir() / "radiomaps").iterdir())


def test_cli_clear_cache(tmp_path: Path) -> None:
    env = {"MPLBACKEND": "Agg", "PATH": "", "RAINUAV_CACHE_DIR": str(tmp_path / "c")}
    folder = tmp_path / "c" / "radiomaps"
    folder.mkdir(parents=True)
    (folder / "0123.npz").write_bytes(b"old map")
    proc = subprocess.run(
        [sys.executable, "-m", "rainuav.radiomap", "--clear-cache"],
        capture_output=True,
        text=True,
        env=env,
        timeout=120,
    )
    assert proc.returncode == 0 and "removed 1 cached map" in proc.stdout
    assert not list(folder.iterdir())


def test_noise_from_bandwidth_and_noise_figure() -> None:
    # docs/physics.md section 9: N = -174 dBm/Hz + 10 log10(B) + NF; 20 MHz and 7 dB give -93.99
    # dBm (PHYSICS rounds to -94); the defaults (10 MHz, 9 dB) give -95 dBm exactly, the
    # previous fixed noise, so existing maps keep their SINR. An explicit noise_dbm wins.
    assert beam_line().replace(bandwidth_hz=20e6, noise_figure_db=7.0).noise_power_dbm == (
        pytest.approx(-174 + 10 * math.log10(20e6) + 7, abs=1e-12)
    )
    assert beam_line().noise_power_dbm == -95.0
    assert beam_line().replace(noise_dbm=-120.0).noise_power_dbm == -120.0
    for change, needle in (
        ({"bandwidth_hz": 0.0}, "bandwidth_hz must be within"),
        ({"noise_figure_db": 31.0}, "noise_figure_db must be within 0..30"),
        ({"noise_figure_db": float("nan")}, "noise_figure_db"),
    ):
        with pytest.raises(rainuav.InvalidInputError, match=needle):
            beam_line().replace(**change)


def test_map_sinr_uses_the_receiver_noise() -> None:
    # One cell: SINR = S / N, so a 30 dB worse noise figure lowers SINR by 30 dB wherever
    # neither value is clipped (1e-9: the same powers, only N differs).
    scn = beam_line(length=200.0, res=10.0)
    quiet = build_radio_map(scn.replace(noise_figure_db=0.0), cache=False)
    loud = build_radio_map(scn.replace(noise_figure_db=30.0), cache=False)
    ok = (quiet.sinr_db < sinr_mod.SIR_CEIL_DB) & (loud.sinr_db > sinr_mod.SIR_FLOOR_DB)
    assert ok.sum() > 10
    np.testing.assert_allclose((quiet.sinr_db - loud.sinr_db)[ok], 30.0, atol=1e-9)


def test_a_rain_map_in_time_is_hashed_by_its_values() -> None:
    # The digest reads a grid (a radar file's rates in time) as its shape and values, where
    # their JSON text took seconds: two scenarios with equal rates share a key, one changed
    # rate or another shape gives another key, and a scenario without grids keeps the key it
    # had (the JSON of its fields).
    import dataclasses
    import hashlib
    import json

    from rainuav.radio.scene.presets import paper
    from rainuav.radio.scene.weather import Medium

    base = paper()
    rates = np.random.default_rng(0).uniform(0.0, 50.0, (4, 30, 40))
    times = [0.0, 60.0, 120.0, 180.0]

    def with_rates(r: np.ndarray):
        m = Medium(kind="map", rate_map_mm_h=r.tolist(), rate_times_s=times)
        return dataclasses.replace(base, medium=m)

    scn = with_rates(rates)
    assert scn.digest() == with_rates(rates.copy()).digest()
    changed = rates.copy()
    changed[3, 29, 39] += 1e-6
    assert with_rates(changed).digest() != scn.digest()
    assert with_rates(rates.reshape(4, 40, 30)).digest() != scn.digest()
    text = json.dumps(base.to_dict(), sort_keys=True)
    assert base.digest() == hashlib.sha256(text.encode()).hexdigest()[:32]
