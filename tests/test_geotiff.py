"""Rain from GeoTIFF: files written by rasterio (GDAL), as radar archives and GIS
tools write them, read into the same rain as the same grid in CF NetCDF; a grid moved by one
pixel moves the rain by one pixel; what the reader cannot place in time or space is refused
in one line."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from rainuav.errors import InvalidInputError
from rainuav.geo import Georef

rasterio = pytest.importorskip("rasterio")  # a test dependency: skipped only outside [test]
from rainuav.radio.scene.radar import read_radar_grid  # noqa: E402
from rainuav.radio.scene.scenario import Area  # noqa: E402
from rasterio.transform import Affine  # noqa: E402

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
G = Georef(47.376, 8.548)
AREA = Area(-500.0, 500.0, -500.0, 500.0, resolution_m=10.0)
TIMES = ["2026-06-01T14:00:00", "2026-06-01T14:00:30", "2026-06-01T14:01:00"]


def from_origin(west: float, north: float, dx: float, dy: float) -> Affine:
    """A north-up transform (rasterio's ``from_origin`` without the affine ``*`` it warns on)."""
    return Affine(dx, 0.0, west, 0.0, -dy, north)


def write_tif(path, values, transform, crs, units="mm/h", times=TIMES, tags=None, unit_tag=False):
    """``values`` (B, H, W), row 0 north, one band per instant ``times`` (band descriptions;
    ``None``: none), units as the band unit (or as a ``units`` tag)."""
    b, h, w = values.shape
    with rasterio.open(path, "w", driver="GTiff", height=h, width=w, count=b, dtype="float64",
                       crs=crs, transform=transform, nodata=-9999.0) as dst:  # fmt: skip
        dst.write(values)
        for k in range(1, b + 1):
            if times is not None:
                dst.set_band_description(k, times[k - 1])
            if units and unit_tag:
                dst.update_tags(k, units=units)
            elif units:
                dst.set_band_unit(k, units)
        if tags:
            dst.update_tags(**tags)
    return path


def blob(x: np.ndarray, y: np.ndarray, x0: float, y0: float, peak: float) -> np.ndarray:
    gx, gy = np.meshgrid(x, y)
    return peak * np.exp(-((gx - x0) ** 2 + (gy - y0) ** 2) / (2 * 150.0**2))


def local_grid() -> tuple[np.ndarray, np.ndarray, str]:
    """Pixel centres (x west to east, y north to south), 10 m, on the scenario's own AEQD."""
    x = np.arange(-800.0, 800.0, 10.0) + 5.0
    y = np.arange(700.0, -700.0, -10.0) - 5.0
    return x, y, rasterio.crs.CRS.from_proj4(G.proj4).to_wkt()


def test_geotiff_reads_as_the_same_grid_in_netcdf(tmp_path) -> None:
    """Three bands (a storm moving east, dates in the band descriptions) give the rain and
    the instants of the same values written as CF NetCDF (1e-9: the same interpolation of
    the same numbers)."""
    import xarray as xr

    x, y, wkt = local_grid()
    vals = np.stack([blob(x, y, 60.0 * k, 50.0, 80.0) for k in range(3)])
    tif = write_tif(tmp_path / "r.tif", vals, from_origin(-800.0, 700.0, 10.0, 10.0), wkt)
    when = np.array(TIMES, "datetime64[s]")
    da = xr.DataArray(vals, dims=("time", "y", "x"), name="rain", attrs={"units": "mm/h"},
                      coords={"time": when, "y": y, "x": x})  # fmt: skip
    ds = da.to_dataset()
    ds["crs"] = xr.DataArray(0, attrs={"crs_wkt": wkt})
    ds["rain"].attrs["grid_mapping"] = "crs"
    ds.to_netcdf(tmp_path / "r.nc", engine="h5netcdf")
    a = read_radar_grid(tif, AREA, G, max_cells=100)
    b = read_radar_grid(tmp_path / "r.nc", AREA, G, max_cells=100)
    np.testing.assert_allclose(np.asarray(a.rate_map_mm_h), np.asarray(b.rate_map_mm_h), atol=1e-9)
    assert a.rate_times_s == b.rate_times_s == [0.0, 30.0, 60.0]
    assert np.asarray(a.rate_map_mm_h).max() > 70.0  # the storm is over the area


def test_a_geotiff_moved_by_one_pixel_moves_the_rain_by_one_pixel(tmp_path) -> None:
    """The transform's origin shifted one pixel east: the same rain one sample east
    (interior, 1e-9), as for NetCDF."""
    x, y, wkt = local_grid()
    vals = blob(x, y, 0.0, 50.0, 80.0)[None]
    runs = []
    for k, west in enumerate((-800.0, -790.0)):
        f = write_tif(tmp_path / f"p{k}.tif", vals, from_origin(west, 700.0, 10.0, 10.0), wkt,
                      times=TIMES[:1])  # fmt: skip
        runs.append(np.asarray(read_radar_grid(f, AREA, G, max_cells=100).rate_map_mm_h))
    np.testing.assert_allclose(runs[1][:, 1:], runs[0][:, :-1], atol=1e-9)


def test_a_folder_of_scans_in_dbz_with_tiff_dates(tmp_path) -> None:
    """A folder of one-band dBZ files on lat/lon (EPSG:4326), each dated by TIFFTAG_DATETIME
    and named out of time order, reads as the scans in time order, converted by
    Marshall-Palmer like the same values in one file (1e-9)."""
    lat = np.arange(47.392, 47.360, -0.0005)
    lon = np.arange(8.530, 8.566, 0.0005)
    tr = from_origin(8.530 - 0.00025, 47.392 + 0.00025, 0.0005, 0.0005)
    z = np.stack([20.0 + 10.0 * k + 0.0 * np.zeros((len(lat), len(lon))) for k in range(3)])
    folder = tmp_path / "scans"
    folder.mkdir()
    for k, name in enumerate(("c.tif", "a.tif", "b.tif")):
        stamp = TIMES[k].replace("-", ":").replace("T", " ")
        write_tif(folder / name, z[k : k + 1], tr, "EPSG:4326", units="dBZ", times=None,
                  tags={"TIFFTAG_DATETIME": stamp}, unit_tag=True)  # fmt: skip
    one = write_tif(tmp_path / "all.tif", z, tr, "EPSG:4326", units="dBZ")
    a = read_radar_grid(folder, AREA, G, max_cells=50)
    b = read_radar_grid(one, AREA, G, max_cells=50)
    assert a.rate_times_s == [0.0, 30.0, 60.0]
    want = (10.0 ** (z[:, 0, 0] / 10.0) / 200.0) ** (1 / 1.6)
    got = np.asarray(a.rate_map_mm_h)
    np.testing.assert_allclose(got.mean(axis=(1, 2)), want, rtol=1e-9)
    np.testing.assert_allclose(got, np.asarray(b.rate_map_mm_h), atol=1e-9)


@pytest.mark.parametrize(
    ("kind", "match"),
    [
        ("nocrs", "has no CRS"),
        ("units", "units must be mm/h or dBZ"),
        ("notime", "band 1 has no time"),
        ("badtime", "not an ISO 8601 date"),
        ("rotated", "must be north-up"),
        ("garbage", "not a readable GeoTIFF"),
        ("small", "must cover the area"),
        ("nodata", "must be finite over the area"),
        ("empty", "holds no .tif"),
        ("mixed", "differ from"),
        ("huge", "GB but this machine has"),
    ],
)
def test_bad_geotiffs_are_refused_in_one_line(tmp_path, kind: str, match: str) -> None:
    x, y, wkt = local_grid()
    vals = np.full((1, len(y), len(x)), 5.0)
    tr = from_origin(-800.0, 700.0, 10.0, 10.0)
    path = tmp_path / "r.tif"
    if kind == "nocrs":
        write_tif(path, vals, tr, None, times=TIMES[:1])
    elif kind == "units":
        write_tif(path, vals, tr, wkt, units="", times=TIMES[:1])
    elif kind == "notime":
        write_tif(path, vals, tr, wkt, times=None)
    elif kind == "badtime":
        write_tif(path, vals, tr, wkt, times=["yesterday"])
    elif kind == "rotated":
        write_tif(path, vals, Affine(10.0, 1.0, -800.0, 0.0, -10.0, 700.0), wkt, times=TIMES[:1])
    elif kind == "garbage":
        path.write_bytes(b"II*\x00 not a tiff at all")
    elif kind == "small":
        write_tif(path, vals[:, :20, :20], tr, wkt, times=TIMES[:1])
    elif kind == "nodata":
        vals[0, 60, 80] = -9999.0
        write_tif(path, vals, tr, wkt, times=TIMES[:1])
    elif kind == "empty":
        path = tmp_path / "scans"
        path.mkdir()
    elif kind == "huge":  # a header claiming 2 x 10^6 x 10^6 pixels: refused before reading
        with rasterio.open(path, "w", driver="GTiff", height=1_000_000, width=1_000_000,
                           count=2, dtype="float32", crs=wkt, transform=tr,
                           tiled=True, sparse_ok=True) as dst:  # fmt: skip
            dst.set_band_description(1, TIMES[0])
            dst.set_band_description(2, TIMES[1])
            dst.set_band_unit(1, "mm/h")
            dst.set_band_unit(2, "mm/h")
    else:
        path = tmp_path / "scans"
        path.mkdir()
        write_tif(path / "a.tif", vals, tr, wkt, times=TIMES[:1])
        write_tif(path / "b.tif", vals[:, :-1], tr, wkt, times=TIMES[1:2])
    with pytest.raises(InvalidInputError, match=match) as err:
        read_radar_grid(path, AREA, G)
    assert "\n" not in str(err.value)


@pytest.mark.slow
@pytest.mark.timeout(120)
def test_fly_takes_a_geotiff(tmp_path) -> None:
    """``fly --weather FILE.tif``: the shipped radar example written as GeoTIFF (EPSG:4326,
    13 bands) flies like the NetCDF file: the same weather, so the same plan's cost (1e-6)."""
    import xarray as xr
    from rainuav.fly import main

    da = xr.open_dataset(EXAMPLES / "radar.nc")["reflectivity"].load()
    lat, lon = da["lat"].values, da["lon"].values
    north = da.isel(lat=slice(None, None, -1)).values.astype(np.float64)
    step = 0.0005
    tr = from_origin(lon[0] - step / 2, lat[-1] + step / 2, step, step)
    times = [str(t)[:19] for t in da["time"].values]
    tif = write_tif(tmp_path / "radar.tif", north, tr, "EPSG:4326", units="dBZ", times=times)
    costs = []
    for name, weather in (("tif", tif), ("nc", EXAMPLES / "radar.nc")):
        out = tmp_path / name
        argv = ["--sites", str(EXAMPLES / "sites.csv"), "--start", "47.3660,8.5380",
                "--goal", "47.3700,8.5420", "--weather", str(weather),
                "--out", str(out)]  # fmt: skip
        assert main(argv) == 0
        costs.append(json.loads((out / "summary.json").read_text())["cost"])
    assert costs[0] == pytest.approx(costs[1], rel=1e-6)


def test_fly_refuses_a_bad_geotiff_in_one_line(tmp_path, capsys) -> None:
    """``fly --weather`` with a GeoTIFF that is not one, and with one without a CRS: exit 2
    and one line naming the file."""
    from rainuav.fly import main

    garbage = tmp_path / "scan.tif"
    garbage.write_bytes(b"II*\x00 not a tiff at all")
    x, y, _ = local_grid()
    nocrs = write_tif(tmp_path / "nocrs.tif", np.ones((1, len(y), len(x))),
                      from_origin(-800.0, 700.0, 10.0, 10.0), None, times=TIMES[:1])  # fmt: skip
    for path, match in ((garbage, "not a readable GeoTIFF"), (nocrs, "has no CRS")):
        argv = ["--sites", str(EXAMPLES / "sites.csv"), "--start", "47.3660,8.5380",
                "--goal", "47.3700,8.5420", "--weather", str(path),
                "--out", str(tmp_path / "o")]  # fmt: skip
        assert main(argv) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and match in err[0] and str(path) in err[0], err
