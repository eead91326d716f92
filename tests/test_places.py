"""Real places: the georeference against pyproj's geodesic, and the
mission files through the parsers real clients use (pymavlink's waypoint loader, the
``geojson`` package's validation, an XML parser for KML, QGroundControl's plan fields)."""

from __future__ import annotations

import json
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest
from rainuav.errors import InvalidInputError
from rainuav.geo import Georef, geodesic_m
from rainuav.missions import (
    MAV_CMD_NAV_LAND,
    MAV_CMD_NAV_TAKEOFF,
    MAV_CMD_NAV_WAYPOINT,
    corners,
    expand,
    geojson_dict,
    kml_text,
    plan_dict,
    wpl_text,
)

ORIGINS = [(52.52, 13.405), (-33.87, 151.21), (78.2, 15.6), (0.0, 179.99), (45.0, -179.99)]


@pytest.mark.parametrize(("lat", "lon"), ORIGINS)
def test_round_trip_within_a_centimetre(lat: float, lon: float) -> None:
    """lat/lon -> scenario metres -> lat/lon returns every point of a 10 km square within
    1 cm (the issue's tolerance; PROJ's inverse is exact to well under a millimetre)."""
    g = Georef(lat, lon)
    rng = np.random.default_rng(0)
    x, y = rng.uniform(-5000, 5000, 200), rng.uniform(-5000, 5000, 200)
    la, lo = g.to_latlon(x, y)
    x2, y2 = g.to_local(la, lo)
    assert np.max(np.hypot(x2 - x, y2 - y)) < 0.01
    la2, lo2 = g.to_latlon(x2, y2)
    np.testing.assert_allclose(g.to_local(la2, lo2), (x, y), atol=0.01)


@pytest.mark.parametrize(("lat", "lon"), ORIGINS)
def test_distances_match_the_geodesic(lat: float, lon: float) -> None:
    """Straight-line distances between sites in the scenario's metres equal the WGS 84
    geodesic (pyproj's Geod, Karney) within 0.1% over a 10 km area (the projection's
    scale error there is about 1e-6)."""
    g = Georef(lat, lon)
    rng = np.random.default_rng(1)
    x, y = rng.uniform(-5000, 5000, (2, 100)), rng.uniform(-5000, 5000, (2, 100))
    la, lo = g.to_latlon(x, y)
    flat = np.hypot(x[0] - x[1], y[0] - y[1])
    geo = geodesic_m(la[0], lo[0], la[1], lo[1])
    np.testing.assert_allclose(flat, geo, rtol=1e-3)


def test_bad_origins_are_refused() -> None:
    with pytest.raises(InvalidInputError, match="lat_deg must be within"):
        Georef(90.0, 0.0)
    with pytest.raises(InvalidInputError, match="lon_deg must be a finite number"):
        Georef(10.0, float("nan"))
    with pytest.raises(InvalidInputError, match="latitude must be in"):
        Georef(10.0, 10.0).to_local(95.0, 10.0)


def lattice_path(rng: np.random.Generator, n: int = 200) -> np.ndarray:
    """A random lattice path of 10 m moves with runs of repeated moves."""
    moves = np.array([[10, 0], [0, 10], [-10, 0], [0, -10]], dtype=float)
    a = rng.integers(0, 4, n // 5).repeat(5)
    return np.vstack([[[123.4, 567.8]], np.array([123.4, 567.8]) + np.cumsum(moves[a], 0)])


def test_corners_fly_the_same_path() -> None:
    """Straight legs between the corners are the lattice path, vertex for vertex."""
    rng = np.random.default_rng(2)
    for _ in range(20):
        path = lattice_path(rng)
        idx = corners(path)
        assert idx[0] == 0 and idx[-1] == len(path) - 1
        np.testing.assert_allclose(expand(path[idx], 10.0), path, atol=1e-9)
        assert len(idx) < len(path)


def test_waypoints_load_in_pymavlink_within_a_decimetre(tmp_path) -> None:
    """``mission.waypoints`` through pymavlink's ``MAVWPLoader``: home, take-off, each
    waypoint within 0.1 m of the planned point (measured in the scenario's metres), landing."""
    from pymavlink import mavwp

    g = Georef(47.376, 8.548)
    path = lattice_path(np.random.default_rng(3))
    pts = path[corners(path)]
    lat, lon = g.to_latlon(pts[:, 0], pts[:, 1])
    home = (float(lat[0]), float(lon[0]))
    f = tmp_path / "mission.waypoints"
    f.write_text(wpl_text(home, np.stack([lat, lon], 1), 100.0))
    loader = mavwp.MAVWPLoader()
    n = loader.load(str(f))
    assert n == len(pts) + 3  # home, take-off, waypoints, landing
    items = [loader.wp(k) for k in range(n)]
    assert [w.command for w in items[1:2]] == [MAV_CMD_NAV_TAKEOFF]
    assert {w.command for w in items[2:-1]} == {MAV_CMD_NAV_WAYPOINT}
    assert items[-1].command == MAV_CMD_NAV_LAND
    got = np.array([[w.x, w.y] for w in items[2:-1]])
    gx, gy = g.to_local(got[:, 0], got[:, 1])
    assert np.max(np.hypot(gx - pts[:, 0], gy - pts[:, 1])) < 0.1
    assert all(w.z == 100.0 for w in items[1:-1]) and all(w.frame == 3 for w in items[1:])


def test_geojson_kml_and_plan_carry_the_path(tmp_path) -> None:
    import geojson

    g = Georef(-33.87, 151.21)
    path = lattice_path(np.random.default_rng(4), 50)
    lat, lon = g.to_latlon(path[:, 0], path[:, 1])
    ll = np.stack([lat, lon], 1)
    sites = [{"site_id": "S1", "lat": lat[0] + 0.001, "lon": lon[0], "height_m": 25.0}]
    props = {"t_s": list(range(len(ll))), "sinr_db": [1.5] * len(ll)}
    d = geojson_dict(ll, 100.0, props, sites, {"cost": 12.5})
    obj = geojson.loads(json.dumps(d))
    assert obj.is_valid, obj.errors()
    line = obj["features"][0]["geometry"]["coordinates"]
    np.testing.assert_allclose(np.array(line)[:, :2], np.stack([lon, lat], 1))
    root = ET.fromstring(kml_text(ll, 100.0, "flight", sites).encode())
    ns = {"k": "http://www.opengis.net/kml/2.2"}
    coords = root.find(".//k:LineString/k:coordinates", ns).text.split()
    kml_pts = np.array([[float(v) for v in c.split(",")] for c in coords])
    np.testing.assert_allclose(kml_pts[:, :2], np.stack([lon, lat], 1))
    assert np.all(kml_pts[:, 2] == 100.0)
    plan = plan_dict((lat[0], lon[0]), ll[corners(path)], 100.0, 10.0)
    assert plan["fileType"] == "Plan" and plan["groundStation"] == "QGroundControl"
    m = plan["mission"]
    for key in ("items", "plannedHomePosition", "firmwareType", "vehicleType", "cruiseSpeed",
                "hoverSpeed", "globalPlanAltitudeMode", "version"):  # fmt: skip
        assert key in m, key
    for it in m["items"]:
        assert it["type"] == "SimpleItem" and len(it["params"]) == 7
    json.dumps(plan, allow_nan=False)  # plain JSON, as QGC reads it


SITES_CSV = """site_id,lat,lon,height_m,azimuth_deg,electrical_tilt_deg,tx_power_dbm,rows
A,47.3760,8.5480,25,0,6,46,8
A,47.3760,8.5480,25,120,6,46,8
A,47.3760,8.5480,25,240,6,46,8
B,47.3850,8.5600,30,90,4,43,
"""


def test_sites_from_csv_and_geojson(tmp_path) -> None:
    """One row per sector: masts at their projected positions, compass azimuths (clockwise
    from north) turned into rainuav's (counter-clockwise from east), downtilts into upward
    tilts; the GeoJSON form of the same list gives the same sites."""
    from rainuav.radio.scene.sites import read_site_rows, sites_from_rows

    g = Georef(47.376, 8.548)
    f = tmp_path / "sites.csv"
    f.write_text(SITES_CSV)
    sites = sites_from_rows(read_site_rows(f), g)
    assert [len(s.cells) for s in sites] == [3, 1]
    assert abs(sites[0].x_m) < 1e-6 and abs(sites[0].y_m) < 1e-6
    bx, by = g.to_local(47.385, 8.56)
    assert (sites[1].x_m, sites[1].y_m) == pytest.approx((bx, by), abs=1e-6)
    assert [c.azimuth_deg for c in sites[0].cells] == [90.0, 330.0, 210.0]
    assert sites[1].cells[0].azimuth_deg == 0.0  # east
    assert sites[0].cells[0].electrical_tilt_deg == -6.0 and sites[1].height_m == 30.0
    feats = []
    for line in SITES_CSV.splitlines()[1:]:
        sid, lat, lon, h, az, tilt, p, rows = line.split(",")
        props = {"site_id": sid, "height_m": float(h), "azimuth_deg": float(az),
                 "electrical_tilt_deg": float(tilt), "tx_power_dbm": float(p)}  # fmt: skip
        if rows:
            props["rows"] = int(rows)
        geom = {"type": "Point", "coordinates": [float(lon), float(lat)]}
        feats.append({"type": "Feature", "geometry": geom, "properties": props})
    gj = tmp_path / "sites.geojson"
    gj.write_text(json.dumps({"type": "FeatureCollection", "features": feats}))
    assert sites_from_rows(read_site_rows(gj), g) == sites


@pytest.mark.parametrize(
    ("text", "match"),
    [
        ("", "no column site_id in the header"),
        ("site_id,lat,lon,height_m,azimuth_deg,electrical_tilt_deg,tx_power_dbm\n",
         "no sectors"),
        (SITES_CSV.replace("47.3850", "north"), r"line 5: column lat must be a number"),
        (SITES_CSV.replace(",43,", ",430,"), r"line 5: column tx_power_dbm must be a number in"),
        (SITES_CSV.replace("B,47.3850", ",47.3850"), "line 5: column site_id is missing"),
        (SITES_CSV.replace("A,47.3760,8.5480,25,240", "A,47.3760,8.5480,28,240"),
         "site A: its sectors disagree"),
        (SITES_CSV.replace(",8\n", ",8.5\n", 1), "line 2: column rows must be an integer"),
    ],
)  # fmt: skip
def test_bad_sites_files_are_refused_naming_row_and_column(tmp_path, text: str, match: str) -> None:
    from rainuav.radio.scene.sites import read_site_rows, sites_from_rows

    f = tmp_path / "sites.csv"
    f.write_text(text)
    with pytest.raises(InvalidInputError, match=match):
        sites_from_rows(read_site_rows(f), Georef(47.376, 8.548))


@pytest.mark.parametrize(
    ("text", "match"),
    [("[1, 2]", "must be a GeoJSON FeatureCollection"), ("{", "not JSON"),
     ('{"type": "FeatureCollection", "features": [{"geometry": null}]}',
      "feature 0: geometry must be a Point")],
)  # fmt: skip
def test_bad_geojson_sites_are_refused(tmp_path, text: str, match: str) -> None:
    from rainuav.radio.scene.sites import read_site_rows

    f = tmp_path / "sites.geojson"
    f.write_text(text)
    with pytest.raises(InvalidInputError, match=match):
        read_site_rows(f)


EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "sites.csv"


@pytest.mark.slow
@pytest.mark.timeout(120)
def test_fly_cli_writes_files_real_clients_load(tmp_path) -> None:
    """``python -m rainuav.fly`` on the shipped example: the mission loads in pymavlink with
    every waypoint within 0.1 m of the planned path's corners, the GeoJSON validates and
    carries per-vertex time, SINR, serving cell and outage, the KML parses, and the summary
    compares the flight with the straight line."""
    import geojson
    from pymavlink import mavwp
    from rainuav.fly import main

    out = tmp_path / "flight"
    argv = ["--sites", str(EXAMPLE), "--start", "47.3660,8.5380", "--goal", "47.3800,8.5560",
            "--rain-rate-mm-h", "25", "--out", str(out)]  # fmt: skip
    assert main(argv) == 0
    for name in ("flight.geojson", "flight.kml", "mission.plan", "mission.waypoints",
                 "flight.png", "summary.json"):  # fmt: skip
        assert (out / name).stat().st_size > 0, name
    summary = json.loads((out / "summary.json").read_text())
    from test_docs import documented_summary_fields

    assert set(summary) <= documented_summary_fields(), set(summary) - documented_summary_fields()
    g = Georef(summary["origin"]["lat"], summary["origin"]["lon"])
    text = (out / "flight.geojson").read_text()
    assert geojson.loads(text).is_valid
    line = json.loads(text)["features"][0]  # full precision (geojson rounds to 6 digits)
    coords = np.array(line["geometry"]["coordinates"])
    x, y = g.to_local(coords[:, 1], coords[:, 0])
    path = np.stack([x, y], 1)
    assert len(path) == summary["moves"] + 1
    for key in ("t_s", "sinr_db", "serving_cell", "outage"):
        assert len(line["properties"][key]) == len(path), key
    loader = mavwp.MAVWPLoader()
    n = loader.load(str(out / "mission.waypoints"))
    assert n == summary["waypoints"] + 3
    wps = np.array([[loader.wp(k).x, loader.wp(k).y] for k in range(2, n - 1)])
    wx, wy = g.to_local(wps[:, 0], wps[:, 1])
    corner_pts = path[corners(path)]
    assert np.max(np.hypot(wx - corner_pts[:, 0], wy - corner_pts[:, 1])) < 0.1
    assert summary["cost"] <= summary["straight_line_cost"] + 1e-9
    ET.fromstring((out / "flight.kml").read_bytes())
    assert json.loads((out / "mission.plan").read_text())["fileType"] == "Plan"


def test_fly_cli_refuses_bad_input_in_one_line(tmp_path, capsys) -> None:
    from rainuav.fly import main

    polar = tmp_path / "polar.csv"
    text = EXAMPLE.read_text()
    for lat in ("47.37000", "47.37900", "47.36400"):
        text = text.replace(lat, "89.99000")
    polar.write_text(text)
    trip = ["--start", "47.3660,8.5380", "--goal", "47.3800,8.5560"]
    cases = [
        (["--sites", str(tmp_path / "none.csv"), *trip], "--sites: no file"),
        (["--sites", str(polar), "--start", "89.99,8.54", "--goal", "89.995,8.55"],
         "lat_deg must be within"),
        (["--sites", str(EXAMPLE), "--altitude-m", "0", *trip], "--altitude-m"),
        (["--sites", str(EXAMPLE), "--start", "47.36,north", "--goal", "47.38,8.55"], "LAT,LON"),
    ]  # fmt: skip
    for extra, match in cases:
        argv = ["--out", str(tmp_path / "o"), *extra]
        try:
            code = main(argv)
        except SystemExit as exit_:  # argparse's own refusal: usage line and error line
            code = exit_.code
        assert code == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert match in err[-1], err
        assert len(err) == 1 or err[0].startswith("usage:"), err  # argparse: usage, then one


def radar_file(path, da_name: str, values, coords: dict, units: str, crs_wkt: str | None = None):
    """A CF NetCDF file of ``values`` (time, y, x) on ``coords`` (written by xarray)."""
    import xarray as xr

    dims = list(coords)
    da = xr.DataArray(values, dims=dims, coords=coords, name=da_name, attrs={"units": units})
    ds = da.to_dataset()
    if crs_wkt is not None:
        ds["crs"] = xr.DataArray(0, attrs={"crs_wkt": crs_wkt})
        ds[da_name].attrs["grid_mapping"] = "crs"
    ds.to_netcdf(path, engine="h5netcdf")
    return path


def blob(x: np.ndarray, y: np.ndarray, x0: float, y0: float, peak: float) -> np.ndarray:
    gx, gy = np.meshgrid(x, y)
    return peak * np.exp(-((gx - x0) ** 2 + (gy - y0) ** 2) / (2 * 150.0**2))


def test_reflectivity_becomes_rain_by_marshall_palmer(tmp_path) -> None:
    """A uniform 30 dBZ field is 5^(1/1.6) = 2.7344 mm/h everywhere (Z = 200 R^1.6); below
    0 dBZ no rain."""
    from rainuav.radio.scene.radar import dbz_to_rate, read_radar_grid
    from rainuav.radio.scene.scenario import Area

    assert dbz_to_rate(30.0) == pytest.approx(2.7344, rel=1e-4)
    assert dbz_to_rate(-5.0) == 0.0
    g = Georef(47.376, 8.548)
    lat = np.linspace(47.36, 47.39, 40)
    lon = np.linspace(8.53, 8.57, 50)
    f = radar_file(tmp_path / "z.nc", "dbz", np.full((1, 40, 50), 30.0),
                   {"time": [0.0], "lat": lat, "lon": lon}, "dBZ")  # fmt: skip
    m = read_radar_grid(f, Area(-500, 500, -500, 500), g)
    np.testing.assert_allclose(np.asarray(m.rate_map_mm_h), 2.7344, rtol=1e-4)


def test_a_grid_moved_by_one_pixel_moves_the_rain_by_one_pixel(tmp_path) -> None:
    """On the scenario's own projection (AEQD at the origin, 10 m pixels on the area's
    sample grid) a storm shifted one pixel east in the file is the same rain one sample
    east in the scenario (interior, 1e-9); on a lat/lon grid its centroid moves by the pixel's
    ground width (within 1%)."""
    from rainuav.radio.scene.radar import read_radar_grid
    from rainuav.radio.scene.scenario import Area

    g = Georef(47.376, 8.548)
    area = Area(-500.0, 500.0, -500.0, 500.0, resolution_m=10.0)
    x = np.arange(-800.0, 800.0, 10.0) + 5.0
    y = np.arange(-700.0, 700.0, 10.0) + 5.0
    wkt = __import__("pyproj").CRS.from_proj4(g.proj4).to_wkt()
    runs = []
    for k, x0 in enumerate((0.0, 10.0)):
        vals = blob(x, y, x0, 50.0, 80.0)[None]
        f = radar_file(tmp_path / f"p{k}.nc", "rain", vals, {"time": [0.0], "y": y, "x": x},
                       "mm/h", wkt)  # fmt: skip
        runs.append(np.asarray(read_radar_grid(f, area, g, max_cells=100).rate_map_mm_h))
    np.testing.assert_allclose(runs[1][:, 1:], runs[0][:, :-1], atol=1e-9)
    lat = np.arange(47.360, 47.392, 0.0005)
    lon = np.arange(8.530, 8.566, 0.0005)
    gx0, gy0 = g.to_local(*np.meshgrid(lat, lon, indexing="ij"))
    cents = []
    for k, shift in enumerate((0, 1)):
        vals = np.roll(80.0 * np.exp(-(gx0**2 + (gy0 - 50) ** 2) / (2 * 80.0**2)), shift, axis=1)
        f = radar_file(tmp_path / f"l{k}.nc", "rain", vals[None],
                       {"time": [0.0], "lat": lat, "lon": lon}, "mm/h")  # fmt: skip
        r = np.asarray(read_radar_grid(f, area, g, max_cells=100).rate_map_mm_h)
        xs = area.x_min_m + (np.arange(r.shape[1]) + 0.5) * 10.0
        cents.append((r.sum(axis=0) * xs).sum() / r.sum())
    phi = np.radians(47.376)  # the parallel's radius on the WGS 84 ellipsoid, N cos(phi)
    n = 6_378_137.0 / np.sqrt(1.0 - 0.00669437999014 * np.sin(phi) ** 2)
    width = np.radians(0.0005) * n * np.cos(phi)
    assert cents[1] - cents[0] == pytest.approx(width, rel=0.01)


def test_bad_radar_grids_are_refused(tmp_path) -> None:
    from rainuav.radio.scene.radar import read_radar_grid
    from rainuav.radio.scene.scenario import Area

    g = Georef(47.376, 8.548)
    x = np.arange(-800.0, 800.0, 10.0)
    coords = {"time": [0.0], "y": x, "x": x}
    vals = np.ones((1, len(x), len(x)))
    f = radar_file(tmp_path / "nocrs.nc", "rain", vals, coords, "mm/h")
    with pytest.raises(InvalidInputError, match="no CRS"):
        read_radar_grid(f, Area(-500, 500, -500, 500), g)
    f = radar_file(tmp_path / "units.nc", "rain", vals, coords, "inch", "x")
    with pytest.raises(InvalidInputError, match="units must be mm/h or dBZ"):
        read_radar_grid(f, Area(-500, 500, -500, 500), g)


@pytest.mark.slow
@pytest.mark.timeout(120)
def test_fly_through_the_shipped_radar_file(tmp_path) -> None:
    """``--weather examples/radar.nc`` (dBZ on lat/lon, 13 scans): a weather that moves, the
    plan in space-time, never worse than the straight line through the same storm. With
    ``--altitudes-m 100:100:1`` the plan among levels in space and time is the same flight (the
    same cost and moves, to 1e-9: the same rewards summed)."""
    from rainuav.fly import main

    out = tmp_path / "flight"
    argv = ["--sites", str(EXAMPLE), "--start", "47.3660,8.5380", "--goal", "47.3700,8.5420",
            "--weather", str(EXAMPLE.with_name("radar.nc"))]  # fmt: skip
    assert main([*argv, "--out", str(out)]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["weather_moves"] is True
    assert summary["cost"] <= summary["straight_line_cost"] + 1e-9
    # The plan's outage with its spread, each move on the slice it lands in: a share between
    # 0 and 1, the independent spread below the fully correlated one.
    chance = summary["outage_chance"]
    assert 0.0 <= chance["expected_outage_share"] <= 1.0
    assert 0.0 <= chance["spread_independent"] <= chance["spread_correlated"] <= 0.5
    assert main([*argv, "--altitudes-m", "100:100:1", "--out", str(tmp_path / "band")]) == 0
    band = json.loads((tmp_path / "band" / "summary.json").read_text())
    assert band["weather_moves"] is True and band["moves"] == summary["moves"]
    assert band["cost"] == pytest.approx(summary["cost"], abs=1e-9)
    assert band["flight_time_s"] == pytest.approx(summary["flight_time_s"])
    # Among levels in a moving weather the maps hold SINR alone: the summary says it has no
    # outage chance, and why, rather than a number.
    assert band["outage_chance"]["spreads"] is None and "SINR alone" in band["outage_chance"]["why"]


def test_a_scenario_carries_its_origin(tmp_path) -> None:
    """``[origin]`` round-trips through TOML and gives the georeference; a scenario without
    one keeps its old form (so its digest, and the map cache, are unchanged)."""
    from rainuav.radio.scene import presets
    from rainuav.radio.scene.scenario import Origin, Scenario

    plain = presets.uma()
    assert "origin" not in plain.to_dict()
    geo = plain.replace(origin=Origin(47.376, 8.548))
    back = Scenario.from_toml_string(geo.to_toml_string())
    assert back == geo and back.georef == Georef(47.376, 8.548)
    lat, lon = back.georef.to_latlon(0.0, 0.0)
    assert (float(lat), float(lon)) == pytest.approx((47.376, 8.548), abs=1e-12)
    with pytest.raises(InvalidInputError, match="lat_deg must be within"):
        Scenario.from_toml_string(plain.replace(origin=Origin(89.5, 0.0)).to_toml_string())


@pytest.mark.slow
def test_fly_area_box(tmp_path, capsys) -> None:
    """``--area S,W,N,E``: the map covers that box; a start outside it is one line."""
    from rainuav.fly import main

    box = "47.3600,8.5300,47.3850,8.5600"
    argv = ["--sites", str(EXAMPLE), "--goal", "47.3700,8.5420", "--area", box]
    assert main([*argv, "--start", "47.3660,8.5380", "--out", str(tmp_path / "a")]) == 0
    s = json.loads((tmp_path / "a" / "summary.json").read_text())
    g = Georef(s["origin"]["lat"], s["origin"]["lon"])
    x, y = g.to_local([47.36, 47.385], [8.53, 8.56])
    x0, x1, y0, y1 = s["area_m"]
    assert x0 <= min(x) < x0 + 10 and x1 - 10 < max(x) <= x1
    assert y0 <= min(y) < y0 + 10 and y1 - 10 < max(y) <= y1
    assert main([*argv, "--start", "47.3500,8.5380", "--out", str(tmp_path / "b")]) == 2
    assert "--start 47.35,8.538 lies outside the --area" in capsys.readouterr().err


def test_a_flyer_flies_the_place_and_is_judged_against_the_optimum(tmp_path) -> None:
    """``fly_place(flyer=...)`` writes the flyer's path; flying the exact plan itself costs
    the optimum to 1e-9 (the cost is charged as the task charges it)."""
    from rainuav.fly.plan import fly_place
    from rainuav.nav import planner
    from rainuav.world.place import place_scenario

    place = place_scenario(EXAMPLE, (47.3660, 8.5380), (47.3700, 8.5420))

    def exact(env):
        return planner.optimal(env, np.asarray(env.cfg.start_m)).path_m, True

    s = fly_place(place, tmp_path / "f", flyer=exact, flown_by="test flyer")
    assert s["flown_by"] == "test flyer"
    assert s["cost"] == pytest.approx(s["optimal_cost"], abs=1e-9)
    assert abs(s["excess_over_optimum"]) < 1e-12
    with pytest.raises(InvalidInputError, match="does not reach the destination"):
        fly_place(place, tmp_path / "g", flyer=lambda env: (np.zeros((2, 2)), False))


def test_fly_policy_must_read_the_weather(tmp_path, capsys) -> None:
    import tomli_w
    from rainuav.fly import main
    from rainuav.rl.config import TrainConfig, to_dict

    run = tmp_path / "run"
    run.mkdir()
    (run / "config.toml").write_text(tomli_w.dumps(to_dict(TrainConfig(out=str(run)))))
    (run / "checkpoint.pt").write_bytes(b"")
    argv = ["--sites", str(EXAMPLE), "--start", "47.3660,8.5380", "--goal", "47.3700,8.5420",
            "--policy", str(run), "--out", str(tmp_path / "o")]  # fmt: skip
    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "fly a network that reads the weather" in err[0]
    # A network that chooses among flight levels does not fly one altitude.
    levels = TrainConfig(out=str(run), observation="weather", altitudes_m="25:115:15")
    (run / "config.toml").write_text(tomli_w.dumps(to_dict(levels)))
    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "chooses among the flight levels 25:115:15 m" in err[0]


def test_the_largest_place_fits_the_pe_march_from_a_corner(tmp_path) -> None:
    """``MAX_SIDE_M`` is the largest area ``fly`` maps: sectors in one corner of a place that
    large, pointing along its edges and across its diagonal with no tilt (the longest
    marches), all fit the ``uma`` settings' PE budget, so no place ``fly`` accepts ends in the
    engine's budget error."""
    from rainuav.radio.engines.grid import march_grid
    from rainuav.world.place import MARGIN_M, MAX_SIDE_M, place_scenario

    g = Georef(47.0, 8.0)
    leg = MAX_SIDE_M - 2 * MARGIN_M - 20.0  # the pixel rounding of the edges
    lat1, lon1 = g.to_latlon(leg, leg)
    rows = ["site_id,lat,lon,height_m,azimuth_deg,electrical_tilt_deg,tx_power_dbm"]
    rows += [f"C,47.0,8.0,25,{az},0,46" for az in (0, 45, 90)]
    (tmp_path / "corner.csv").write_text("\n".join(rows) + "\n")
    place = place_scenario(tmp_path / "corner.csv", (47.0, 8.0), (float(lat1), float(lon1)))
    a = place.scenario.area
    assert max(a.x_max_m - a.x_min_m, a.y_max_m - a.y_min_m) <= MAX_SIDE_M
    assert min(a.x_max_m - a.x_min_m, a.y_max_m - a.y_min_m) > MAX_SIDE_M - 100.0
    (site,) = place.scenario.sites
    grids = [march_grid(place.scenario, site, c) for c in site.cells]
    budget = place.scenario.pe.budget_gpoints
    assert all(gr is not None and gr.gpoints <= budget for gr in grids)
