"""Terrain: the DEM read onto the area, the diffraction over each path's profile against
independent references, maps over a DEM in two CRSs, shifts, and bad DEMs refused in one line
(docs/physics.md section 12)."""

from __future__ import annotations

import dataclasses
import json
import warnings
from pathlib import Path

import numpy as np
import pytest
from rainuav import _core
from rainuav.errors import InvalidInputError
from rainuav.radio.outputs.maps import build_radio_map
from rainuav.radio.scene.scenario import Area, Cell, Origin, Scenario, Site, TerrainFile
from rainuav.radio.scene.terrain import flight_heights, not_flyable, scenario_terrain

rasterio = pytest.importorskip("rasterio")
from rasterio.transform import Affine  # noqa: E402


def from_origin(west: float, north: float, dx: float, dy: float) -> Affine:
    """A north-up transform (rasterio's ``from_origin`` without the affine ``*`` it warns on)."""
    return Affine(dx, 0.0, west, 0.0, -dy, north)


ORIGIN = Origin(lat_deg=47.30, lon_deg=8.50)
C0 = 299_792_458.0


def ridge(x: np.ndarray, y: np.ndarray, x0: float = 600.0) -> np.ndarray:
    """A rounded north-south ridge 150 m high at ``x0`` m east of the origin, on a 300 m
    plain."""
    del y
    return 300.0 + 150.0 * np.exp(-(((x - x0) / 120.0) ** 2))


def write_dem(path: Path, values: np.ndarray, transform, crs, **kw) -> Path:
    """A one-band GeoTIFF (rows north to south)."""
    profile = {
        "driver": "GTiff",
        "height": values.shape[0],
        "width": values.shape[1],
        "count": 1,
        "dtype": kw.pop("dtype", "float32"),
        "crs": crs,
        "transform": transform,
        **kw,
    }
    units = profile.pop("units", None)
    with rasterio.open(path, "w", **profile) as dst:
        dst.write(values.astype(profile["dtype"]), 1)
        if units:
            dst.units = (units,)
    return path


def dem_4326(path: Path, surface, margin_m: float = 300.0, cell_deg: float = 5e-5) -> Path:
    """``surface(x, y)`` (local metres of ORIGIN) sampled at the cell centres of a lon/lat grid
    covering the test area with a margin."""
    from rainuav.geo import Georef

    g = Georef(ORIGIN.lat_deg, ORIGIN.lon_deg)
    lat0, lon0 = g.to_latlon(-margin_m, -margin_m)
    lat1, lon1 = g.to_latlon(1200.0 + margin_m, 800.0 + margin_m)
    w = int(np.ceil((lon1 - lon0) / cell_deg))
    h = int(np.ceil((lat1 - lat0) / cell_deg))
    lons = lon0 + (np.arange(w) + 0.5) * cell_deg
    lats = lat1 - (np.arange(h) + 0.5) * cell_deg
    la, lo = np.meshgrid(lats, lons, indexing="ij")
    x, y = g.to_local(la, lo)
    return write_dem(path, surface(x, y), from_origin(lon0, lat1, cell_deg, cell_deg), "EPSG:4326")


def dem_utm(path: Path, surface, margin_m: float = 300.0, cell_m: float = 5.0) -> Path:
    """The same in UTM zone 32N."""
    import pyproj
    from rainuav.geo import Georef

    g = Georef(ORIGIN.lat_deg, ORIGIN.lon_deg)
    to_utm = pyproj.Transformer.from_crs("EPSG:4326", "EPSG:32632", always_xy=True)
    corners = [
        g.to_latlon(x, y) for x in (-margin_m, 1200 + margin_m) for y in (-margin_m, 800 + margin_m)
    ]
    e, n = to_utm.transform([c[1] for c in corners], [c[0] for c in corners])
    e0, n1 = min(e), max(n)
    w, h = int(np.ceil((max(e) - e0) / cell_m)), int(np.ceil((n1 - min(n)) / cell_m))
    ee = e0 + (np.arange(w) + 0.5) * cell_m
    nn = n1 - (np.arange(h) + 0.5) * cell_m
    gn, ge = np.meshgrid(nn, ee, indexing="ij")
    lon, lat = to_utm.transform(ge, gn, direction="INVERSE")
    x, y = g.to_local(lat, lon)
    return write_dem(path, surface(x, y), from_origin(e0, n1, cell_m, cell_m), "EPSG:32632")


def scenario(dem: Path | None, site_x: float = 200.0, **area: object) -> Scenario:
    cell = Cell(azimuth_deg=0.0, tilt_deg=0.0, antenna="tr38901")
    return Scenario(
        name="terrain",
        freq_hz=4.9e9,
        area=Area(0.0, 1200.0, 0.0, 800.0, altitude_m=60.0, resolution_m=20.0, **area),  # type: ignore[arg-type]
        sites=[Site(site_x, 400.0, 25.0, [cell])],
        engine="ray",
        origin=ORIGIN,
        # No unresolved roughness: the DEM is the ground (these tests check the geometry;
        # tests/test_ground_roughness.py the roughness).
        terrain=None if dem is None else TerrainFile(str(dem), roughness_m=0.0),
    )


# -- the diffraction against independent references ------------------------------------------


def test_knife_edge_j_is_within_0_2_db_of_the_exact_fresnel_integral() -> None:
    # P.526 eq. (31) is an approximation of the exact knife edge: the loss of
    # |F(nu)| = |(1 + j)/2 [(1/2 - C(nu)) - j (1/2 - S(nu))]| (P.526 eq. 26); its stated
    # accuracy is about 0.2 dB over nu >= -0.78 (docs/physics.md section 12).
    from scipy.special import fresnel

    nu = np.linspace(-0.78, 5.0, 2001)
    s, c = fresnel(nu)
    exact = -20 * np.log10(np.hypot(1 - c - s, c - s) / 2)
    j = _core.knife_edge_loss_db(nu)
    assert np.max(np.abs(j - exact)) < 0.2


def _bullington_by_hand(d, h, dist, hts, hrs, lam):
    """docs/physics.md section 12 written out directly (km and the 0.002 factor, as P.526)."""
    ce = 1 / 8500.0
    di, dk = d / 1000.0, dist / 1000.0
    g = h + 500 * ce * di * (dk - di)
    s_tim = np.max((g - hts) / di)
    s_tr = (hrs - hts) / dk
    if s_tim < s_tr:
        nu = np.max(
            (g - (hts * (dk - di) + hrs * di) / dk) * np.sqrt(0.002 * dk / (lam * di * (dk - di)))
        )
    else:
        s_rim = np.max((g - hrs) / (dk - di))
        dbp = (hrs - hts + s_rim * dk) / (s_tim + s_rim)
        nu = (hts + s_tim * dbp - (hts * (dk - dbp) + hrs * dbp) / dk) * np.sqrt(
            0.002 * dk / (lam * dbp * (dk - dbp))
        )
    luc = 0.0 if nu <= -0.78 else 6.9 + 20 * np.log10(np.sqrt((nu - 0.1) ** 2 + 1) + nu - 0.1)
    return luc + (1 - np.exp(-luc / 6)) * (10 + 0.02 * dk)


PROFILES = {
    "rounded hill": lambda d: 120.0 * np.exp(-(((d - 1500.0) / 250.0) ** 2)),
    "two ridges": lambda d: (
        90.0 * np.exp(-(((d - 900.0) / 80.0) ** 2)) + 110.0 * np.exp(-(((d - 2100.0) / 80.0) ** 2))
    ),
    "three ridges": lambda d: sum(
        a * np.exp(-(((d - c) / 70.0) ** 2)) for a, c in ((70, 700), (130, 1500), (80, 2300))
    ),
    "line of sight": lambda d: 15.0 * np.exp(-(((d - 1500.0) / 300.0) ** 2)),
}
ENDS = [(25.0, 100.0), (30.0, 60.0), (40.0, 250.0)]


@pytest.mark.parametrize("name", list(PROFILES))
@pytest.mark.parametrize("freq_ghz", [4.9, 28.0])
def test_bullington_against_the_formulas_by_hand(name: str, freq_ghz: float) -> None:
    # The core's construction against the formulas of docs/physics.md section 12 written out in
    # km in the test: the same arithmetic, so within 0.01 dB.
    d = np.arange(10.0, 3000.0, 10.0)
    h = PROFILES[name](d)
    lam = C0 / (freq_ghz * 1e9)
    for hts, hrs in ENDS:
        got = _core.bullington_loss(
            d, h, d_total_m=3000.0, h_ts_m=hts, h_rs_m=hrs, wavelength_m=lam
        )
        want = _bullington_by_hand(d, h, 3000.0, hts, hrs, lam)
        assert abs(got[0] - want) < 0.01, (name, hts, hrs, got[0], want)


def _pycraf():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            import pycraf.pathprof as pp
            from astropy import units as u
            from pycraf import conversions as cnv
        except ImportError:
            pytest.fail("pycraf is a test dependency: pip install --no-deps pycraf (make build)")
    return pp, u, cnv


@pytest.mark.parametrize("name", list(PROFILES))
def test_bullington_against_pycraf_p452(name: str) -> None:
    # pycraf's ITU-R P.452-16 diffraction (an independent implementation, delta-Bullington
    # with its spherical-Earth term) on the same profile, its effective Earth set to 8500 km
    # (delta_N so that k50 = 8500 / 6371). Within 0.5 dB (the tolerance); measured:
    # equal to the printed digits, the spherical term being 0 at these heights.
    pp, u, cnv = _pycraf()
    step, dist = 10.0, 3000.0
    dists = np.arange(0.0, dist + step / 2, step)
    heights = PROFILES[name](dists)
    k50 = 8500.0 / 6371.0
    lam = C0 / 4.9e9
    for htg, hrg in ENDS:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            prop = pp.PathProp(
                4.9 * u.GHz, 293 * u.K, 1013 * u.hPa, 8.50 * u.deg, 47.3 * u.deg,
                8.54 * u.deg, 47.3 * u.deg, htg * u.m, hrg * u.m, step * u.m, 50 * u.percent,
                delta_N=157 * (1 - 1 / k50) * cnv.dimless / u.km, N0=325 * cnv.dimless,
                hprof_dists=dists / 1000 * u.km, hprof_heights=heights * u.m,
                hprof_bearing=90 * u.deg, hprof_backbearing=270 * u.deg,
            )  # fmt: skip
            theirs = pp.loss_diffraction(prop)[0].to_value(u.dB)
        ours = _core.bullington_loss(
            dists[1:-1], heights[1:-1], d_total_m=dist, h_ts_m=heights[0] + htg,
            h_rs_m=heights[-1] + hrg, wavelength_m=lam,
        )[0]  # fmt: skip
        assert abs(ours - theirs) < 0.5, (name, htg, hrg, ours, theirs)


# -- maps over a DEM --------------------------------------------------------------------------


@pytest.fixture(scope="module")
def dems(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    d = tmp_path_factory.mktemp("dems")
    return {
        "ridge_4326": dem_4326(d / "ridge_4326.tif", ridge),
        "ridge_utm": dem_utm(d / "ridge_utm.tif", ridge),
        "ridge_4326_shifted": dem_4326(
            d / "ridge_4326_shifted.tif", lambda x, y: ridge(x, y, 620.0)
        ),
        "flat_0": dem_4326(d / "flat_0.tif", lambda x, y: 0.0 * x, cell_deg=2e-4),
        "flat_437": dem_4326(d / "flat_437.tif", lambda x, y: 437.0 + 0.0 * x, cell_deg=2e-4),
    }


def test_a_flat_dem_at_any_height_is_the_flat_map(dems: dict[str, Path]) -> None:
    # Heights are measured from the terrain, so a flat DEM is today's flat ground: the same
    # received power at every pixel to rounding (1e-6 dB).
    flat = build_radio_map(scenario(None), cache=False)
    for key in ("flat_0", "flat_437"):
        rm = build_radio_map(scenario(dems[key]), cache=False)
        assert np.max(np.abs(rm.rss_dbm - flat.rss_dbm)) < 1e-6, key
        assert not not_flyable(scenario(dems[key])).any()


def test_the_same_ridge_in_two_crs_gives_the_same_map(dems: dict[str, Path]) -> None:
    # The same analytic surface written in EPSG:4326 (5e-5 degree cells) and in UTM 32N (5 m
    # cells): each is resampled bilinearly, so the terrains differ by the two grids'
    # interpolation errors (under a metre on this ridge). Tolerances: 0.5 dB median, 2 dB p99.
    a = build_radio_map(scenario(dems["ridge_4326"]), cache=False).rss_dbm
    b = build_radio_map(scenario(dems["ridge_utm"]), cache=False).rss_dbm
    diff = np.abs(a - b)
    assert np.median(diff) < 0.5 and np.percentile(diff, 99) < 2.0, (
        np.median(diff),
        np.percentile(diff, 99),
    )


def test_a_dem_and_its_sites_shifted_by_one_pixel_shift_the_map(dems: dict[str, Path]) -> None:
    # The ridge 20 m (one pixel) further east and the site with it: the map moves one pixel
    # east (compared where both are defined; 0.5 dB median, 2 dB p99, the resampling's).
    a = build_radio_map(scenario(dems["ridge_4326"]), cache=False).rss_dbm[0]
    b = build_radio_map(scenario(dems["ridge_4326_shifted"], site_x=220.0), cache=False).rss_dbm[0]
    diff = np.abs(a[:, :-1] - b[:, 1:])
    assert np.median(diff) < 0.5 and np.percentile(diff, 99) < 2.0


def test_the_ridge_shadows_the_far_side(dems: dict[str, Path]) -> None:
    # Site at x = 200 m, 25 m above the plain; the ridge's crest at x = 600 m stands 150 m
    # over the plain, the UAV 60 m above the terrain: beyond the ridge (x >= 800 m) the
    # direct ray diffracts. Against the flat map at the same heights, the shadow costs more
    # than 15 dB (median), and nothing is lost in front of the ridge (x <= 400 m).
    scn = scenario(dems["ridge_4326"])
    hill = build_radio_map(scn, cache=False).rss_dbm[0]
    flat = build_radio_map(scenario(dems["flat_0"]), cache=False).rss_dbm[0]
    x, _ = scn.area.centres()
    behind, front = x >= 800.0, x <= 400.0
    assert np.median(flat[:, behind] - hill[:, behind]) > 15.0
    assert np.median(np.abs(flat[:, front] - hill[:, front])) < 1.0


def test_heights_mask_and_msl(dems: dict[str, Path]) -> None:
    scn = scenario(dems["ridge_4326"])
    t = scenario_terrain(scn)
    assert t is not None and t.dx_m <= 10.0 and t.dy_m <= 10.0
    x, y = scn.area.centres()
    # Terrain-following: 60 m above the ridge's surface everywhere (bilinear nodes at 10 m
    # against the analytic surface: within 1.5 m).
    fh = flight_heights(scn)
    assert np.max(np.abs(fh - (ridge(x[None, :], y[:, None]) + 60.0))) < 1.5
    # Clearance 10 m: terrain-following never reaches it; at 400 m above sea level the ridge
    # (up to 450 m) is not flyable where terrain + 10 m reaches 400 m, and the plain is.
    assert not not_flyable(scn).any()
    msl = scenario(dems["ridge_4326"], altitude_reference="msl").replace(
        area=Area(
            0.0, 1200.0, 0.0, 800.0, altitude_m=400.0, resolution_m=20.0, altitude_reference="msl"
        )
    )
    mask = not_flyable(msl)
    col = mask.any(axis=0)
    assert col[np.abs(x - 600.0) < 40].all() and not col[np.abs(x - 600.0) > 300].any()
    assert np.all(flight_heights(msl) == 400.0)


def test_the_cache_key_follows_the_dem_contents(tmp_path: Path, dems: dict[str, Path]) -> None:
    p = tmp_path / "dem.tif"
    p.write_bytes(dems["flat_0"].read_bytes())
    a = scenario(p).digest()
    p.write_bytes(dems["flat_437"].read_bytes())
    assert scenario(p).digest() != a
    assert scenario(dems["flat_0"]).digest() == a  # same contents, other name


def test_terrain_in_toml_is_relative_to_the_file(tmp_path: Path, dems: dict[str, Path]) -> None:
    (tmp_path / "dem.tif").write_bytes(dems["flat_0"].read_bytes())
    text = scenario(dems["flat_0"]).to_toml_string().replace(str(dems["flat_0"]), "dem.tif")
    (tmp_path / "s.toml").write_text(text)
    scn = Scenario.from_toml(tmp_path / "s.toml")
    assert Path(scn.terrain.file) == tmp_path / "dem.tif"  # type: ignore[union-attr]


# -- bad DEMs ---------------------------------------------------------------------------------


def _bad_dems(d: Path) -> dict[str, tuple[Path, str]]:
    t = from_origin(8.49, 47.32, 1e-4, 1e-4)
    ok = np.full((400, 400), 300.0)
    holes = ok.copy()
    holes[150:250, 150:250] = -32768
    text = d / "notes.tif"
    text.write_text("not a raster")
    return {
        "no CRS": (write_dem(d / "nocrs.tif", ok, t, None), "has no CRS"),
        "feet": (write_dem(d / "feet.tif", ok, t, "EPSG:4326", units="ft"), "'ft'"),
        "nodata": (write_dem(d / "nodata.tif", holes, t, "EPSG:4326", nodata=-32768,
                             dtype="int16"), "nodata"),
        "too high": (write_dem(d / "high.tif", ok + 9300.0, t, "EPSG:4326"), "-500..9000"),
        "rotated": (write_dem(d / "rot.tif", ok, Affine(1e-4, 1e-5, 8.49, 1e-5, -1e-4, 47.32),
                              "EPSG:4326"), "north-up"),
        "not a raster": (text, "not a readable GeoTIFF"),
        "elsewhere": (write_dem(d / "far.tif", ok, from_origin(9.5, 47.32, 1e-4, 1e-4),
                                "EPSG:4326"), "does not cover the area"),
    }  # fmt: skip


def test_bad_dems_are_refused_in_one_line_naming_the_file(tmp_path: Path) -> None:
    for what, (path, words) in _bad_dems(tmp_path).items():
        with pytest.raises(InvalidInputError) as err:
            build_radio_map(scenario(path), cache=False)
        msg = str(err.value)
        assert "\n" not in msg and str(path) in msg and words in msg, (what, msg)


def test_a_huge_dem_is_refused_before_reading(tmp_path: Path) -> None:
    # 100 000 x 100 000 cells of 2 cm over the area (a sparse file of a few kilobytes): the
    # window over the area alone would need tens of GB, refused before anything is read.
    from rainuav.geo import Georef

    g = Georef(ORIGIN.lat_deg, ORIGIN.lon_deg)
    local = g.proj4
    path = tmp_path / "huge.tif"
    with rasterio.open(
        path, "w", driver="GTiff", height=100_000, width=100_000, count=1, dtype="int16",
        crs=local, transform=from_origin(-100.0, 1900.0, 0.02, 0.02), tiled=True,
        sparse_ok=True, nodata=-32768,
    ):  # fmt: skip
        pass
    assert path.stat().st_size < 50e6
    with pytest.raises(InvalidInputError, match=r"needs .* GB"):
        build_radio_map(scenario(path), cache=False)


def test_terrain_needs_an_origin_and_a_floor_for_the_march(dems: dict[str, Path]) -> None:
    with pytest.raises(InvalidInputError, match=r"terrain needs \[origin\]"):
        scenario(dems["flat_0"]).replace(origin=None)
    with pytest.raises(InvalidInputError, match="engine 'hybrid' over terrain needs a ground"):
        scenario(dems["flat_0"]).replace(engine="hybrid", ground="none")


# -- the parabolic equation over terrain --------------------------------------------------------


def _beam_scenario(dem: Path | None, engine: str) -> Scenario:
    """One narrow beam (6 degrees, 3 degrees up) east from x = 200 m over the test area at 30 m
    above the ground: its 40 dB cone fits the march's budget, so the PE carries the whole
    pattern over most of the pixels in front of it."""
    cell = Cell(azimuth_deg=0.0, tilt_deg=3.0, antenna="gaussian", beamwidth_deg=6.0,
                beamwidth_v_deg=6.0)  # fmt: skip
    return scenario(dem).replace(
        engine=engine, sites=[Site(200.0, 400.0, 25.0, [cell])],
        area=Area(0.0, 1200.0, 0.0, 800.0, altitude_m=30.0, resolution_m=20.0),
    )  # fmt: skip


@pytest.fixture(scope="module")
def low_ridge(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A smooth ridge 60 m high at x = 600 m on a 360 m plain."""
    d = tmp_path_factory.mktemp("low_ridge")
    return dem_4326(
        d / "low.tif", lambda x, y: 300.0 + 60.0 * np.exp(-(((x - 600.0) / 120.0) ** 2))
    )


@pytest.mark.slow
def test_the_march_over_a_flat_dem_is_the_flat_march(dems: dict[str, Path]) -> None:
    # The hybrid engine over a flat DEM at 437 m: the march's floor is the DEM, nothing stands
    # on it, the receiver rows are the flat ones: the same map as without a DEM (1e-3 dB; the
    # terrain's heights pass through float32 GeoTIFF values; measured 0.0006 dB).
    flat = build_radio_map(_beam_scenario(None, "hybrid"), cache=False)
    dem = build_radio_map(_beam_scenario(dems["flat_437"], "hybrid"), cache=False)
    assert flat.pe_share.max() > 0.5  # the PE carries part of the map
    # Within 80 dB of the strongest pixel (far below it, behind the beam, a two-ray null
    # turns rounding in the gains' directions into dB).
    live = flat.rss_dbm > flat.rss_dbm.max() - 80.0
    assert np.max(np.abs(dem.rss_dbm - flat.rss_dbm)[live]) < 1e-3


@pytest.mark.slow
def test_the_march_over_a_smooth_ridge_against_the_rays(low_ridge: Path) -> None:
    # Where the PE carries the whole pattern (its share of the hybrid map above 0.9): in front
    # of the ridge (x <= 450 m) the march and the rays agree within 1 dB (median; measured
    # 0.04 dB, p90 0.7 dB). In the ridge's shadow (x >= 800 m) the march loses more than the
    # rays: measured median 6.4 dB, p90 14.8 dB. The rays' Bullington loss is a knife edge at
    # the crest plus an empirical correction; the march diffracts over the ridge's rounded
    # shape itself (a rounded crest costs more than a knife edge: ITU-R P.526 section 4.2
    # adds a term for its radius) and sees the slopes' reflections, which the rays drop.
    # Bounds: the median within 0..12 dB of the rays.
    hyb = build_radio_map(_beam_scenario(low_ridge, "hybrid"), cache=False)
    ray = build_radio_map(_beam_scenario(low_ridge, "ray"), cache=False)
    x, _ = hyb.scenario.area.centres()
    full = hyb.pe_share[0] > 0.9
    front = full & (x[None, :] <= 450.0)
    shadow = full & (x[None, :] >= 800.0)
    assert front.sum() >= 10 and shadow.sum() >= 100
    d = hyb.rss_dbm[0] - ray.rss_dbm[0]
    assert abs(np.median(d[front])) < 1.0
    assert -12.0 < np.median(d[shadow]) < 0.0


@pytest.mark.slow
def test_radiomap_cli_over_a_dem(tmp_path: Path, dems: dict[str, Path], capsys) -> None:
    # The command line: a good DEM maps (radiomap.npz written last); a bad one is one line on
    # stderr and exit 2, nothing written.
    from rainuav import radiomap

    toml = tmp_path / "place.toml"
    scenario(None).to_toml(toml)
    out = tmp_path / "maps"
    rc = radiomap.main(
        ["--config", str(toml), "--terrain", str(dems["flat_437"]), "--out", str(out), "--no-cache"]
    )
    assert rc == 0 and (out / "radiomap.npz").is_file()
    bad = _bad_dems(tmp_path / "bad" if (tmp_path / "bad").mkdir() is None else tmp_path)
    out2 = tmp_path / "maps2"
    capsys.readouterr()
    rc = radiomap.main(
        ["--config", str(toml), "--terrain", str(bad["feet"][0]), "--out", str(out2)]
    )
    err = capsys.readouterr().err.strip()
    assert rc == 2 and len(err.splitlines()) == 1 and "feet.tif" in err, err
    assert not (out2 / "radiomap.npz").exists()


def test_obstacles_count_wherever_they_touch_a_pixel() -> None:
    # The height map's cells against each pixel by brute force (every cell overlapping the
    # pixel's square), on grids finer and coarser than the map; boxes over the pixels they
    # touch.
    from rainuav.radio.scene.presets import uma
    from rainuav.radio.scene.scenario import Building
    from rainuav.radio.scene.terrain import obstacle_pixel_max

    rng = np.random.default_rng(0)
    for rows, cols in [(7, 13), (450, 333), (3, 1)]:
        hm = rng.uniform(0, 50, (rows, cols))
        scn = uma(height_map_m=hm.tolist())
        h, w = scn.area.shape
        want = np.zeros((h, w))
        for i in range(h):
            for j in range(w):
                r0, r1 = int(np.floor(i * rows / h)), min(int(np.ceil((i + 1) * rows / h)), rows)
                c0, c1 = int(np.floor(j * cols / w)), min(int(np.ceil((j + 1) * cols / w)), cols)
                want[i, j] = hm[r0:r1, c0:c1].max()
        assert np.array_equal(obstacle_pixel_max(scn), want)
    box = uma(buildings=[Building(995.0, 1011.0, 500.0, 510.0, 70.0)])
    got = obstacle_pixel_max(box)
    assert set(zip(*np.nonzero(got), strict=True)) == {(50, 99), (50, 100), (50, 101)}


def test_the_mask_reads_only_the_buildings_that_can_close_a_pixel(dems: dict[str, Path]) -> None:
    # `not_flyable` intersects with the pixels only the buildings at least the lowest flight
    # height less the clearance and the highest ground tall: against every building intersected
    # (the mask from `obstacle_pixel_max` with none left out), over the ridge with the height
    # above the ground (60 m: the ridge's 150 m of relief leave none out) and above sea level
    # (500 m), and over flat ground. 60 boxes 5-120 m tall; some pixels closed each time.
    from rainuav.radio.scene.scenario import Building
    from rainuav.radio.scene.terrain import obstacle_pixel_max

    rng = np.random.default_rng(3)
    boxes = []
    for _ in range(60):
        x, y = rng.uniform(0.0, 1150.0), rng.uniform(0.0, 750.0)
        boxes.append(Building(x, x + rng.uniform(8, 50), y, y + rng.uniform(8, 50),
                              float(rng.uniform(5.0, 120.0))))  # fmt: skip
    msl = {"altitude_reference": "msl"}
    for dem, area, left_out in [(dems["ridge_4326"], {}, False), (dems["ridge_4326"], msl, True),
                                (None, {}, True)]:  # fmt: skip
        scn = scenario(dem, **area).replace(buildings=boxes)
        if area:
            scn = scn.replace(area=dataclasses.replace(scn.area, altitude_m=500.0))
        a, t = scn.area, scenario_terrain(scn)
        ground = np.zeros(a.shape) if t is None else t.pixel_max(a.shape)
        flight = flight_heights(scn)
        every = ground + obstacle_pixel_max(scn) + a.clearance_m >= flight
        mask = not_flyable(scn)
        assert np.array_equal(mask, every)
        assert mask.any() and not mask.all()
        lowest = flight.min() - a.clearance_m - ground.max()
        assert any(b.height_m < lowest for b in boxes) == left_out, lowest


# -- flights that keep out of what they may not enter ------------------------------------------


def _walled_map(tmp_path: Path):
    """A 100 m wall (a height map) across x = 700..720 m but for the top 100 m, under a UAV at
    60 m with 10 m clearance: the wall's pixels are not flyable."""
    hm = np.zeros((40, 60))
    hm[:35, 35] = 100.0
    scn = scenario(None).replace(height_map_m=hm.tolist())
    rm = build_radio_map(scn, cache=False)
    return scn, rm


def test_flights_never_enter_what_is_not_flyable(tmp_path: Path) -> None:
    # The map carries the wall as not flyable (and keeps it through save and load); the
    # environment ends a move into it as a move out of the area (the out-of-bounds penalty);
    # the exact planner goes round through the gap; the straight line hits the wall and is
    # reported as not arriving; the planner's return is the environment's along its path.
    from rainuav.nav.env import UAVNavEnv
    from rainuav.nav.planner import optimal, straight_line
    from rainuav.radio.outputs.mapdata import RadioMap

    _, rm = _walled_map(tmp_path)
    assert rm.not_flyable is not None
    assert rm.not_flyable[:35, 35].all() and rm.not_flyable.sum() == 35
    back = RadioMap.load(rm.save(tmp_path / "walled.npz"))
    assert np.array_equal(back.not_flyable, rm.not_flyable)
    env = UAVNavEnv(rm, goal_m=(1100.0, 400.0), min_db=-5.0)
    start = np.array([105.0, 405.0])
    plan = optimal(env, start)
    assert plan.return_ > 0  # arrived
    assert not env.field.not_flyable[
        np.clip((plan.path_m[:, 1] // 20).astype(int), 0, 39),
        np.clip((plan.path_m[:, 0] // 20).astype(int), 0, 59),
    ].any()
    assert plan.path_m[:, 1].max() > 700.0  # through the gap
    # The environment pays the same along the plan.
    env.reset(options={"start_m": start})
    ret = 0.0
    for a in plan.actions:
        _, r, term, _, _ = env.step(int(a))
        ret += r
    assert term and abs(ret - plan.return_) < 1e-9
    line = straight_line(env, start)
    assert line.return_ < -env.cfg.out_of_bounds_penalty / 2  # it flew into the wall
    env.reset(options={"start_m": (695.0, 405.0)})
    _, r, term, _, info = env.step(0)  # +x: into the wall
    assert term and not info["arrived"] and r < -env.cfg.out_of_bounds_penalty / 2
    with pytest.raises(InvalidInputError, match="may not fly"):
        env.reset(options={"start_m": (710.0, 405.0)})
    with pytest.raises(InvalidInputError, match="may not fly"):
        UAVNavEnv(rm, goal_m=(710.0, 400.0))
    # Sampled starts avoid the wall.
    starts = [env.sample_start(np.random.default_rng(k)) for k in range(300)]
    assert not any(700.0 <= s[0] < 720.0 and s[1] < 700.0 for s in starts)


# -- fly over terrain ----------------------------------------------------------------------------

EXAMPLE_SITES = Path(__file__).resolve().parents[1] / "examples" / "sites.csv"
HILL = (47.3730, 8.5470)


def _ground(lat: np.ndarray, lon: np.ndarray, ridge: bool) -> np.ndarray:
    """A 400 m plain with a 150 m hill at HILL (radius 200 m), or a ridge through HILL running
    north-west to south-east (across every route from the south-west to the north-east)."""
    dy = (lat - HILL[0]) * 111_200.0
    dx = (lon - HILL[1]) * 111_200.0 * np.cos(np.radians(HILL[0]))
    r2 = ((dx + dy) / np.sqrt(2.0)) ** 2 if ridge else dx**2 + dy**2
    return 400.0 + 150.0 * np.exp(-r2 / 200.0**2)


def _zurich_hill_dem(path: Path, ridge: bool = False) -> Path:
    """A DEM in SRTM's form (EPSG:4326, int16 metres, 1e-4 degree cells) round the example
    sites: :func:`_ground`."""
    cell = 1e-4
    lat1, lon0 = 47.40, 8.50
    lats = lat1 - (np.arange(600) + 0.5) * cell
    lons = lon0 + (np.arange(900) + 0.5) * cell
    la, lo = np.meshgrid(lats, lons, indexing="ij")
    z = _ground(la, lo, ridge)
    return write_dem(path, np.round(z), from_origin(lon0, lat1, cell, cell), "EPSG:4326",
                     dtype="int16", nodata=-32768)  # fmt: skip


@pytest.mark.slow
def test_fly_over_terrain_writes_heights_above_sea_level(tmp_path: Path) -> None:
    # Terrain-following at 100 m over the hill: the mission (read back through pymavlink)
    # flies MAV_FRAME_GLOBAL heights, each waypoint the terrain under it plus 100 m (0.5 m:
    # the file's int16 heights, bilinear), and the straight climb or descent between two
    # waypoints keeps at least the 10 m clearance over the highest point of every pixel on the
    # way.
    from pymavlink import mavwp
    from rainuav.fly import main
    from rainuav.geo import Georef
    from rainuav.missions import MAV_FRAME_GLOBAL

    dem = _zurich_hill_dem(tmp_path / "ridge.tif", ridge=True)
    out = tmp_path / "flight"
    argv = ["--sites", str(EXAMPLE_SITES), "--start", "47.3660,8.5380", "--goal",
            "47.3800,8.5560", "--terrain", str(dem), "--out", str(out)]  # fmt: skip
    assert main(argv) == 0
    summary = json.loads((out / "summary.json").read_text())
    g = Georef(summary["origin"]["lat"], summary["origin"]["lon"])
    loader = mavwp.MAVWPLoader()
    n = loader.load(str(out / "mission.waypoints"))
    assert n == summary["waypoints"] + 3
    items = [loader.wp(k) for k in range(1, n - 1)]  # take-off and the waypoints
    assert all(it.frame == MAV_FRAME_GLOBAL for it in items)
    wx, wy = g.to_local(np.array([it.x for it in items[1:]]), np.array([it.y for it in items[1:]]))
    lat, lon = np.array([it.x for it in items[1:]]), np.array([it.y for it in items[1:]])
    ground = _ground(lat, lon, ridge=True)
    alts = np.array([it.z for it in items[1:]])
    assert np.max(np.abs(alts - (ground + 100.0))) < 0.5 + 1.0  # int16 rounding, bilinear
    assert alts.max() - alts.min() > 50.0  # it climbs over the hill
    plan = json.loads((out / "mission.plan").read_text())["mission"]
    assert plan["globalPlanAltitudeMode"] == 2
    # Between waypoints, along the flown lattice path: the linear height against the
    # terrain (clearance 10 m; 1 m for the int16 file's resolution).
    line = json.loads((out / "flight.geojson").read_text())["features"][0]
    coords = np.array(line["geometry"]["coordinates"])
    under = _ground(coords[:, 1], coords[:, 0], ridge=True)
    px, py = g.to_local(coords[:, 1], coords[:, 0])
    s_path = np.concatenate([[0], np.cumsum(np.hypot(np.diff(px), np.diff(py)))])
    s_wp = np.array(
        [s_path[np.argmin(np.hypot(px - x, py - y))] for x, y in zip(wx, wy, strict=True)]
    )
    flown = np.interp(s_path, s_wp, alts)
    assert np.min(flown - under) >= 10.0 - 1.0
    # Every leg the autopilot flies, sampled every metre against the ground: the planned 100 m
    # above it within HOLD_M (1 m more: the file's int16 heights, and the DEM's bilinear
    # surface between the checks every quarter move).
    from rainuav.missions import HOLD_M

    worst = 0.0
    for k in range(len(wx) - 1):
        n = max(2, int(np.hypot(wx[k + 1] - wx[k], wy[k + 1] - wy[k])) + 1)
        f = np.linspace(0.0, 1.0, n)
        la, lo = g.to_latlon(wx[k] + f * (wx[k + 1] - wx[k]), wy[k] + f * (wy[k + 1] - wy[k]))
        above = alts[k] + f * (alts[k + 1] - alts[k]) - _ground(la, lo, ridge=True)
        worst = max(worst, float(np.max(np.abs(above - 100.0))))
    assert worst <= HOLD_M + 1.0, worst


@pytest.mark.slow
def test_fly_refuses_a_start_where_it_may_not_fly(tmp_path: Path, capsys) -> None:
    # 480 m above sea level: the hill's top (550 m) is not flyable; a start on it is refused
    # in one line, exit 2, nothing written; a flight round it is planned.
    from rainuav.fly import main

    dem = _zurich_hill_dem(tmp_path / "hill.tif")
    base = ["--sites", str(EXAMPLE_SITES), "--terrain", str(dem), "--altitude-reference",
            "msl", "--altitude-m", "480"]  # fmt: skip
    out = tmp_path / "on_hill"
    capsys.readouterr()
    rc = main([*base, "--start", f"{HILL[0]},{HILL[1]}", "--goal", "47.3800,8.5560",
               "--out", str(out)])  # fmt: skip
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and len(err) == 1 and "may not fly" in err[0] and "--start" in err[0], err
    assert not (out / "summary.json").exists()
    out = tmp_path / "round"
    assert main([*base, "--start", "47.3660,8.5380", "--goal", "47.3800,8.5560",
                 "--out", str(out)]) == 0  # fmt: skip
    coords = np.array(
        json.loads((out / "flight.geojson").read_text())["features"][0]["geometry"]["coordinates"]
    )
    ground = _ground(coords[:, 1], coords[:, 0], ridge=False)
    assert np.all(ground + 10.0 < 480.0 + 1.0)  # never over ground within the clearance
    summary = json.loads((out / "summary.json").read_text())
    # The straight line runs into the hill: reported as not arriving, with no cost.
    assert summary["straight_line_arrives"] is False and summary["straight_line_cost"] is None


# -- maps out as GeoTIFF ---------------------------------------------------------------------------


SIX_BANDS = ("sinr_db", "rss_serving_dbm", "serving_cell", "not_flyable", "rss_serving_std_db",
             "rss_serving_sample_std_db")  # fmt: skip
"""A physics map's GeoTIFF bands from radiomap: every map's four and the prior's two spreads."""


@pytest.mark.slow
def test_maps_out_as_geotiff_read_back_at_the_right_place(tmp_path: Path) -> None:
    # A georeferenced map written by `radiomap` (the walled height map, so some pixels are not
    # flyable): rasterio reads every band back at the place each pixel stands (a pixel's
    # centre transformed to lon/lat and into the file's CRS lands in the same pixel) and value
    # (float32 of the map's), and `rio info` (rasterio's command line over GDAL, as QGIS reads
    # the file) shows the CRS, the band names and the nodata value.
    import subprocess
    import sys

    from rainuav import radiomap
    from rainuav.geo import Georef
    from rainuav.radio.outputs.maptiff import NODATA

    hm = np.zeros((40, 60))
    hm[:35, 35] = 100.0
    scn = scenario(None).replace(height_map_m=hm.tolist())
    toml = tmp_path / "walled.toml"
    scn.to_toml(toml)
    out = tmp_path / "maps"
    assert radiomap.main(["--config", str(toml), "--out", str(out), "--no-cache"]) == 0
    rm = build_radio_map(scn, cache=False)
    from rainuav.radio.measured.prior import prior_spread

    local, sample = prior_spread(rm)
    tif = out / "radiomap.tif"
    with rasterio.open(tif) as src:
        # the four bands of every map, and the prior's two spreads a physics map carries
        assert src.descriptions == SIX_BANDS
        assert src.nodata == NODATA and src.count == 6 and (src.height, src.width) == (40, 60)
        bands = src.read()
        # Three pixels by their centres' latitude and longitude.
        g = Georef(ORIGIN.lat_deg, ORIGIN.lon_deg)
        x, y = scn.area.centres()
        import pyproj

        to_file = pyproj.Transformer.from_crs("EPSG:4326", src.crs, always_xy=True)
        for i, j in [(0, 0), (20, 35), (39, 59)]:
            lat, lon = g.to_latlon(x[j], y[i])
            fx, fy = to_file.transform(lon, lat)
            r, c = src.index(fx, fy)
            assert np.float32(rm.sinr_db[i, j]) == bands[0, r, c]
            assert bands[3, r, c] == float(rm.not_flyable[i, j])
            k = rm.serving_cell[i, j]
            assert bands[2, r, c] == (k if k >= 0 else NODATA)
            assert np.float32(rm.rss_dbm[k, i, j]) == bands[1, r, c]
            if k >= 0:  # the prior's spreads of the serving cell
                assert np.float32(local[k, i, j]) == bands[4, r, c]
                assert np.float32(sample[k, i, j]) == bands[5, r, c]
        assert bands[3].sum() == rm.not_flyable.sum() == 35
    # `rio info` as its console script runs it (rasterio.rio.main:main_group).
    rio = "import sys; from rasterio.rio.main import main_group; sys.exit(main_group())"
    info = subprocess.run([sys.executable, "-c", rio, "info", str(tif)],
                          capture_output=True, text=True, check=True)  # fmt: skip
    meta = json.loads(info.stdout)
    assert meta["descriptions"] == list(SIX_BANDS)
    assert meta["nodata"] == NODATA
    assert 'PROJECTION["Azimuthal_Equidistant"]' in meta["crs"]
    assert 'PARAMETER["latitude_of_center",47.3]' in meta["crs"]


def test_storms_over_terrain_every_slice_is_its_static_map(dems: dict[str, Path]) -> None:
    # A 100 mm/h rain cell moving at 12 m/s across the ridge, 28 GHz: each slice of the map in
    # time (the rays traced once over the terrain, the rain added per instant along a fan of
    # lines from each site) against a static build over the same DEM of the weather frozen at
    # that instant. Tolerance 0.05 dB at every pixel (the rain integral's, as on flat ground).
    from rainuav.radio.outputs.timemap import build_radio_map_series
    from rainuav.radio.scene.weather import Medium, RainCell

    cell = RainCell(300.0, 400.0, 200.0, 100.0, vx_m_s=12.0)
    scn = scenario(dems["ridge_4326"]).replace(
        freq_hz=28e9, medium=Medium(kind="cells", rain_rate_mm_h=2.0, cells=[cell])
    )
    times = np.array([0.0, 30.0, 60.0])
    series = build_radio_map_series(scn, times, cache=False)
    for k, t in enumerate(times):
        ref = build_radio_map(scn.replace(medium=scn.medium.at(t)), cache=False)
        live = ref.rss_dbm > -200.0
        d = np.abs(series.rss_dbm[k].astype(float) - ref.rss_dbm)[live]
        assert d.max() < 0.05, (t, d.max())
    assert not np.array_equal(series.rss_dbm[0], series.rss_dbm[-1])  # the rain moved


def test_real_heights_itu_r_p1511_over_zurich(tmp_path: Path) -> None:
    # Real terrain: ITU-R P.1511-2's topographic heights (above mean sea level, 1/12 degree
    # grid; the itur package ships them), the window round Zurich written as a GeoTIFF in
    # EPSG:4326 with the grid's own cell centres. The heights our reader puts on the area's
    # nodes (pyproj to lat/lon, rasterio's window, bilinear between cell centres) against
    # scipy's linear interpolation on the P.1511 grid itself at the same latitudes and
    # longitudes: within 0.01 m (rounding; the same rule read two independent ways). Then a
    # map over it: terrain 400-1000 m, every pixel received.
    import os

    import itur
    from rainuav.geo import Georef
    from rainuav.ground import read_dem
    from scipy.interpolate import RegularGridInterpolator

    data = Path(os.path.dirname(itur.__file__)) / "data" / "1511"
    lat = np.load(data / "v2_lat.npz")["arr_0"][:, 0]  # 90.125 down to -90.125
    lon = np.load(data / "v2_lon.npz")["arr_0"][0]  # -180.125 up to 180.125
    topo = np.load(data / "v2_topo.npz")["arr_0"]
    rows = np.flatnonzero((lat > 46.9) & (lat < 47.7))
    cols = np.flatnonzero((lon > 8.1) & (lon < 8.9))
    window = topo[np.ix_(rows, cols)]
    step = 1.0 / 12.0
    tif = write_dem(tmp_path / "p1511_zurich.tif", window,
                    from_origin(lon[cols[0]] - step / 2, lat[rows[0]] + step / 2, step, step),
                    "EPSG:4326")  # fmt: skip
    scn = scenario(None)
    g = Georef(ORIGIN.lat_deg, ORIGIN.lon_deg)
    t = read_dem(tif, g, scn.area.bounds, scn.area.shape)
    xs = t.x0_m + t.dx_m * np.arange(t.heights_m.shape[1])
    ys = t.y0_m + t.dy_m * np.arange(t.heights_m.shape[0])
    gx, gy = np.meshgrid(xs, ys)
    la, lo = g.to_latlon(gx, gy)
    ref = RegularGridInterpolator((lat[rows][::-1], lon[cols]), window[::-1], method="linear")
    want = ref(np.stack([la.ravel(), lo.ravel()], axis=1)).reshape(la.shape)
    assert np.max(np.abs(t.heights_m - want)) < 0.01
    assert 400.0 < t.heights_m.min() and t.heights_m.max() < 1000.0
    rm = build_radio_map(scenario(tif), cache=False)
    assert np.all(rm.rss_dbm > -200.0)
