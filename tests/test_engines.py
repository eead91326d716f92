"""The ray and hybrid engines (issue: physical radio maps): PE against rays, rain along rays,
convergence, rain raising and lowering SINR, clip shares and thresholds of the presets, and the
antennas cells name.

Speed-sensitive choices: the PE comparisons use two paper cells on a 20 m grid (each march
still resolves the full beam; only the map is coarser), and the preset-wide checks use the
ray engine (the PE and the rays agree inside the cone, tested here, and the PE adds nothing
to the clip share or to the threshold shares that the rays would not)."""

from __future__ import annotations

import math

import numpy as np
import pytest
import rainuav
from rainuav import medium
from rainuav.radio import build_radio_map, presets
from rainuav.radio.engines.ray_engine import ground_permittivity
from rainuav.radio.scene.scenario import Area, Cell, Medium, PESettings, RainCell, Scenario, Site
from scipy.integrate import quad

pytestmark = pytest.mark.timeout(300)

C0 = 299_792_458.0


def _two_paper_cells(**kw: object) -> Scenario:
    base = presets.paper(0.0)
    fields = {
        "sites": base.sites[:2],
        "area": Area(resolution_m=20.0),
        "engine": "hybrid",
    }
    fields.update(kw)
    return base.replace(**fields)


@pytest.fixture(scope="module")
def pe_and_rays() -> tuple[rainuav.radio.RadioMap, rainuav.radio.RadioMap]:
    """Two of the paper's cells in clear air by the hybrid engine and by the rays alone (built
    once: three tests read them)."""
    scn = _two_paper_cells()
    return build_radio_map(scn, cache=False), build_radio_map(scn.replace(engine="ray"))


@pytest.mark.slow
def test_pe_and_rays_agree_inside_the_cone(pe_and_rays) -> None:
    # Two independent methods: the split-step march of the cell's pattern and two rays over
    # the same PEC ground. Tolerance: 1 dB on 95% of the pixels the PE carries alone (the
    # issue's target; residuals come from the PE's pixel box versus the rays' sinc average
    # of the ground fringes, and from the f32 march). Measured: 99% within 1 dB.
    hyb, ray = pe_and_rays
    for m in range(len(hyb.rss_dbm)):
        inside = hyb.pe_share[m] > 0.99
        assert inside.sum() > 50
        d = hyb.rss_dbm[m][inside] - ray.rss_dbm[m][inside]
        assert np.mean(np.abs(d) < 1.0) >= 0.95, np.percentile(np.abs(d), [50, 95])
        assert abs(np.median(d)) < 0.2


@pytest.mark.slow
def test_hybrid_is_continuous_across_the_seam(pe_and_rays) -> None:
    # Along the seam (where the PE's share passes from 1 to 0) the hybrid map must not jump:
    # neighbouring pixels differ by no more than they do in the ray map plus 1 dB (95% of
    # the seam), and the map stays near the ray map there: within 1 dB on 90% of the seam
    # pixels (the residual is the PE against the rays on a beam's steep flank, where the
    # pattern falls ~8 dB per degree).
    hyb, ray = pe_and_rays
    for m in range(len(hyb.rss_dbm)):
        seam = (hyb.pe_share[m] > 0.05) & (hyb.pe_share[m] < 0.95)
        assert seam.sum() > 20
        d = hyb.rss_dbm[m] - ray.rss_dbm[m]
        assert np.mean(np.abs(d[seam]) < 1.0) >= 0.90
        jump = np.abs(np.diff(hyb.rss_dbm[m], axis=1)) - np.abs(np.diff(ray.rss_dbm[m], axis=1))
        band = seam[:, 1:] | seam[:, :-1]
        assert np.percentile(jump[band], 95) < 1.0


@pytest.mark.slow  # the module's PE map (10 s), which the fast tier does not build
def test_engine_record_and_cone_report(pe_and_rays) -> None:
    hyb, ray = pe_and_rays
    assert hyb.pe_share.shape == hyb.rss_dbm.shape
    assert 0.0 <= hyb.pe_share.min() and hyb.pe_share.max() <= 1.0
    assert np.all(ray.pe_share == 0) and np.all(ray.pe_cone_deg == 0)
    # The paper beam's 40 dB cone: 7.9 degrees across, 12.9 in height (the 5 degree tilt
    # adds), within the one-sample margin of the cone search.
    assert np.allclose(hyb.pe_cone_deg, [[7.9, 12.9]] * 2, atol=0.3)


@pytest.mark.slow
def test_raising_the_pe_budget_changes_little(pe_and_rays) -> None:
    # Convergence in the cone: a cone narrowed by a small budget against the full 40 dB cone.
    # SINR within 0.5 dB on 95% of the pixels.
    full = pe_and_rays[0]
    small = build_radio_map(_two_paper_cells(pe=PESettings(budget_gpoints=0.05)), cache=False)
    assert np.all(small.pe_cone_deg < full.pe_cone_deg)
    d = np.abs(small.sinr_db - full.sinr_db)
    assert np.mean(d < 0.5) >= 0.95


def test_halving_the_pixel_changes_little() -> None:
    # The uma map at 20 m pixels against 10 m pixels averaged 2 x 2 (in power): each pixel is
    # the local mean, so the two must agree. SINR within 0.5 dB on 95% of the pixels.
    coarse = build_radio_map(presets.uma(0.0, area=Area(resolution_m=20.0), engine="ray"))
    fine = build_radio_map(presets.uma(0.0, area=Area(resolution_m=10.0), engine="ray"))
    p = 10 ** (fine.rss_dbm / 10)
    m, h, w = p.shape
    p2 = p.reshape(m, h // 2, 2, w // 2, 2).mean(axis=(2, 4))
    s = p2.max(axis=0)
    noise = 10 ** (fine.scenario.noise_power_dbm / 10)
    sinr = 10 * np.log10(s / (p2.sum(axis=0) - s + noise))
    assert np.mean(np.abs(sinr - coarse.sinr_db) < 0.5) >= 0.95


def _one_cell(medium_: Medium, freq_hz: float = 28e9, ground: str = "none") -> Scenario:
    return Scenario(
        freq_hz=freq_hz,
        sites=[
            Site(
                x_m=100.0,
                y_m=1000.0,
                cells=[Cell(azimuth_deg=0.0, tilt_deg=0.0, antenna="tr38901")],
            )
        ],
        area=Area(resolution_m=50.0),
        medium=medium_,
        ground=ground,
        engine="ray",
    )


def test_ray_rain_is_gamma_times_path_length() -> None:
    # Homogeneous rain: attenuation = gamma (rainuav.medium, independent of the ray code)
    # x the 3-D path length; to 0.01 dB as the issue asks (the code is exact to rounding).
    clear = build_radio_map(_one_cell(Medium(kind="clear")), cache=False)
    rain = build_radio_map(_one_cell(Medium(kind="homogeneous", rain_rate_mm_h=50.0)), cache=False)
    gamma = medium.specific_attenuation(28e9, 50.0) / 1000.0
    xx, yy = np.meshgrid(clear.x_m - 100.0, clear.y_m - 1000.0)
    d = np.sqrt(xx**2 + yy**2 + 75.0**2)
    att = clear.rss_dbm[0] - rain.rss_dbm[0]
    assert np.max(np.abs(att - gamma * d)) < 0.01


def test_ray_rain_through_a_rain_cell_is_the_path_integral() -> None:
    # A Gaussian rain cell: the attenuation of the direct ray equals
    # (d / rho) integral gamma(R(x(s), y(s))) ds along the ground track, computed here by
    # adaptive quadrature on the exact rate (scipy) with gamma from rainuav.medium: 0.01 dB.
    cell = RainCell(x_m=1000.0, y_m=1100.0, radius_m=400.0, peak_rate_mm_h=100.0)
    weather = Medium(kind="cells", rain_rate_mm_h=2.0, cells=[cell])
    clear = build_radio_map(_one_cell(Medium(kind="clear")), cache=False)
    rain = build_radio_map(_one_cell(weather), cache=False)
    rm = medium.RainMedium(28e9)
    for i, j in [(20, 30), (25, 39), (5, 20), (35, 10)]:
        x, y = clear.x_m[j], clear.y_m[i]
        rho = math.hypot(x - 100.0, y - 1000.0)

        def gamma(t: float, x: float = x, y: float = y) -> float:
            px, py = 100.0 + t * (x - 100.0), 1000.0 + t * (y - 1000.0)
            r = 2.0 + float(cell.rate(px, py))
            return float(rm.specific_attenuation(r)) / 1000.0

        integral = quad(gamma, 0.0, 1.0, epsabs=1e-9, limit=200)[0] * rho
        want = integral * math.hypot(rho, 75.0) / rho
        got = clear.rss_dbm[0, i, j] - rain.rss_dbm[0, i, j]
        assert abs(got - want) < 0.01, (i, j, got, want)


@pytest.mark.slow
def test_pe_rain_agrees_with_the_rays_inside_the_cone(pe_and_rays) -> None:
    # The PE's attenuation (an effective complex index in the march) against the rays' gamma
    # x length at pixels the PE carries alone: within 0.1 dB (the tolerance).
    clear, ray_clear = pe_and_rays
    rain_scn = presets.with_rain(_two_paper_cells(), 100.0)
    pe_rain = build_radio_map(rain_scn, cache=False)
    ray_rain = build_radio_map(rain_scn.replace(engine="ray"), cache=False)
    inside = clear.pe_share[0] > 0.99
    a_pe = (clear.rss_dbm[0] - pe_rain.rss_dbm[0])[inside]
    a_ray = (ray_clear.rss_dbm[0] - ray_rain.rss_dbm[0])[inside]
    # The rays' loss in homogeneous rain is gamma x the direct path (the ground-reflected ray
    # is a small part of the power in the cone): 100 mm/h at 4.9 GHz is 0.35 dB/km, 0.28 dB
    # over the median 0.81 km. Measured ratio 1 +- 4e-5 (5-95%); 1% allows for the reflected
    # ray's longer path where it matters.
    site = rain_scn.sites[0]
    xx, yy = np.meshgrid(clear.x_m, clear.y_m)
    dz = rain_scn.area.altitude_m - site.height_m
    d_km = np.sqrt((xx - site.x_m) ** 2 + (yy - site.y_m) ** 2 + dz**2)[inside] / 1e3
    gamma = rain_scn.medium.rain_medium(rain_scn.freq_hz, rain_scn.polarization)
    ratio = a_ray / (gamma.specific_attenuation(100.0) * d_km)
    assert 0.99 < np.percentile(ratio, 5) and np.percentile(ratio, 95) < 1.01
    assert np.percentile(np.abs(a_pe - a_ray), 95) < 0.1


@pytest.mark.slow
def test_rain_raises_sinr_where_interference_limited() -> None:
    # uma at 100 m sees every sector in line of sight: interference-limited (noise far below
    # the interference), so rain suppresses the distant interferers more than the near
    # server. An independent two-ray estimate (docs/physics.md section 9) gives a median +3.2 dB
    # at 50 mm/h, 28 GHz, and under 0.2 dB at 4.9 GHz; we require the sign and size: median
    # above +1 dB at 28 GHz, below 0.2 dB in magnitude at 4.9 GHz.
    for freq, lo, hi in ((28e9, 1.0, 6.0), (4.9e9, -0.2, 0.2)):
        clear = build_radio_map(presets.uma(0.0, freq, engine="ray"))
        rain = build_radio_map(presets.uma(50.0, freq, engine="ray"))
        d = np.median(rain.sinr_db - clear.sinr_db)
        assert lo < d < hi, (freq, d)
        # Interference-limited: the noise is well below the interference in clear air.
        p = 10 ** (clear.rss_dbm / 10)
        s = p.max(axis=0)
        interference_dbm = 10 * np.log10(np.median(p.sum(axis=0) - s))
        assert interference_dbm - clear.scenario.noise_power_dbm > 15.0


def test_rain_lowers_sinr_where_noise_limited() -> None:
    # One low-power site far from most of the area: the server is near the noise floor and
    # nothing else interferes, so SINR falls with rain by about the server's path loss.
    sector = Cell(azimuth_deg=45.0, tilt_deg=0.0, antenna="array", rows=8, tx_power_dbm=0.0)
    scn = presets.uma(0.0, 28e9, sites=[Site(x_m=50.0, y_m=50.0, cells=[sector])], engine="ray")
    clear = build_radio_map(scn, cache=False)
    rain = build_radio_map(presets.with_rain(scn, 50.0), cache=False)
    assert np.median(clear.sinr_db) < 20.0  # near the noise floor
    d = rain.sinr_db - clear.sinr_db
    assert np.median(d) < -5.0  # 50 mm/h at 28 GHz: ~9 dB/km over ~1.5 km
    assert np.all(d <= 1e-9)


@pytest.mark.parametrize("name", sorted(presets.PRESETS))
def test_presets_have_few_clips_and_a_threshold_in_the_middle(name: str) -> None:
    scn = presets.PRESETS[name](rain_rate_mm_h=0.0).replace(engine="ray")
    scn = presets.with_rain(scn, 0.0)
    rm = build_radio_map(scn)
    v = rm.sinr_db
    clipped = np.mean((v <= -40.0) | (v >= 60.0))
    assert clipped <= 0.01
    below = np.mean(v < presets.SINR_THRESHOLDS_DB[name])
    assert 0.2 <= below <= 0.8, below


def test_dielectric_ground_reflects_less_than_pec() -> None:
    # P.527 medium-dry soil at 4.9 GHz: eps about 13 - 1.5j (P.2040 fit); a real soil
    # reflects less than a conductor, so the ground-reflected power drops.
    eps = ground_permittivity("medium-dry", 4.9e9)
    assert 10 < eps.real < 15 and -3 < eps.imag < -0.5
    pec = build_radio_map(presets.uma(0.0, engine="ray"))
    soil = build_radio_map(presets.uma(0.0, engine="ray", ground="medium-dry"))
    assert np.median(soil.rss_dbm.max(axis=0)) < np.median(pec.rss_dbm.max(axis=0))
    with pytest.raises(rainuav.InvalidInputError, match="engine 'pe' needs ground"):
        build_radio_map(presets.uma(0.0, engine="pe", ground="medium-dry"), cache=False)


def test_cells_name_their_antenna_and_round_trip(tmp_path) -> None:
    scn = presets.uma(0.0)
    path = scn.to_toml(tmp_path / "uma.toml")
    back = Scenario.from_toml(path)
    assert back == scn and back.digest() == scn.digest()
    c = back.sites[0].cells[0]
    assert (c.antenna, c.rows, c.electrical_tilt_deg) == ("array", 8, -10.0)
    assert presets.paper().sites[0].cells[0].floor_db == presets.PAPER_FLOOR_DB


@pytest.mark.parametrize(
    ("change", "needle"),
    [
        (lambda s: setattr(s.sites[0].cells[0], "rows", -1), "cells[0].rows"),
        (lambda s: setattr(s.sites[0].cells[0], "antenna", "dish"), "cells[0].antenna"),
        (lambda s: setattr(s, "bandwidth_hz", 0.0), "bandwidth_hz"),
        (lambda s: setattr(s, "noise_figure_db", 31.0), "noise_figure_db"),
        (lambda s: setattr(s, "engine", "fdtd"), "engine"),
        (lambda s: setattr(s, "ground", "swamp"), "ground"),
    ],
)
def test_bad_antenna_and_engine_fields_are_named(change, needle) -> None:
    scn = presets.uma(0.0)
    change(scn)
    with pytest.raises(rainuav.InvalidInputError, match=needle.replace("[", r"\[")):
        scn.check()


def test_a_non_finite_gain_table_is_named() -> None:
    from rainuav.radio.scene.cell import Pattern

    bad = Pattern([-10.0, 10.0], [-10.0, 10.0], [[0.0, float("nan")], [0.0, 0.0]])
    with pytest.raises(rainuav.InvalidInputError, match=r"cells\[0\]\.pattern"):
        presets.paper(sites=[Site(x_m=500.0, y_m=500.0, cells=[Cell(pattern=bad)])])


@pytest.mark.slow
def test_an_isotropic_antenna_has_the_widest_cone_and_the_hybrid_maps_it() -> None:
    # A pattern flat over the whole half-space is all peak: the march takes the widest cone
    # (sines 0.95) instead of failing on an empty one, and the hybrid map is finite (100 m x
    # 60 m: the widest cone's march is the costliest a metre; 80% of the pixels are the PE's).
    from rainuav.radio.engines.grid import _dynamic_range_cone
    from rainuav.radio.reference.tracer import ISOTROPIC

    cell = Cell(azimuth_deg=0.0, tilt_deg=0.0, pattern=ISOTROPIC, tx_power_dbm=0.0)
    assert _dynamic_range_cone(cell.key(), 0.0, 40.0) == (0.95, 0.95)
    scn = Scenario(
        freq_hz=4.9e9, engine="hybrid", medium=Medium(kind="clear"),
        area=Area(0.0, 100.0, -30.0, 30.0, altitude_m=20.0, resolution_m=10.0),
        sites=[Site(10.0, 0.0, 25.0, [cell])],
    )  # fmt: skip
    rm = build_radio_map(scn, cache=False)
    assert np.isfinite(rm.rss_dbm).all() and rm.pe_share.max() > 0.5
