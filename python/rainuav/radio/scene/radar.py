"""Rain from a georeferenced grid, as weather radars and nowcasts deliver it: a NetCDF (CF) file of
rain rate or reflectivity on (time, lat, lon) or on projected (time, y, x) with its CRS, or GeoTIFF
(a file with one band per instant, or a folder of them: read by
[`rainuav.radio.scene.geotiff`][rainuav.radio.scene.geotiff] into the same form), reprojected onto a
georeferenced scenario's area.

- **Coordinates.** Either 1-D ``lat``/``lon`` (or ``latitude``/``longitude``) coordinates, in
  degrees (WGS 84), or 1-D ``x``/``y`` with the data variable's ``grid_mapping`` attribute
  naming a variable that holds the CRS as ``crs_wkt`` or ``spatial_ref`` (CF 1.7, what GDAL,
  rioxarray and most radar products write). A grid without either is refused: its positions
  would be a guess.
- **Units.** ``mm/h`` (the spellings of
  [`rainuav.radio.scene.rategrid.UNITS`][rainuav.radio.scene.rategrid.UNITS]) or reflectivity in
  ``dBZ``, converted by the Marshall-Palmer relation ``Z = 200 R^1.6`` (Z in mm^6/m^3, R in mm/h;
  Marshall and Palmer 1948, the default of most radar software for stratiform rain): ``R =
  (10^(dBZ/10) / 200)^(1/1.6)``. Reflectivity below
  [`NO_ECHO_DBZ`][rainuav.radio.scene.radar.NO_ECHO_DBZ] (0 dBZ, 0.04 mm/h) is no rain, as radar
  products mark clutter-free no-echo pixels.
- **Reprojection.** Each sample point of the area (the centres of a grid of at most ``max_cells`` a
  side over it, as [`rainuav.radio.scene.rategrid`][rainuav.radio.scene.rategrid] samples) is taken
  to latitude and longitude through the scenario's [`rainuav.geo.Georef`][rainuav.geo.Georef], then
  into the file's CRS (pyproj), and the file is interpolated bilinearly there (xarray's ``interp``).
  The file must cover the area.

Needs the ``weather`` and ``geo`` extras (xarray, h5netcdf, pyproj; rasterio for GeoTIFF).
"""

from __future__ import annotations

import os
from typing import Any

import numpy as np
import numpy.typing as npt

from rainuav._checks import check_fits
from rainuav.errors import InvalidInputError
from rainuav.geo import Georef, pyproj_module
from rainuav.radio.scene.geotiff import is_geotiff, open_geotiff
from rainuav.radio.scene.rategrid import (
    UNITS,
    _open,
    _rain_variable,
    _seconds,
    rate_medium,
    sample_grid,
)
from rainuav.radio.scene.scenario import Area
from rainuav.radio.scene.weather import MAX_RATE_MM_H, Medium

__all__ = ["DBZ_UNITS", "MP_A", "MP_B", "NO_ECHO_DBZ", "dbz_to_rate", "read_radar_grid"]

MP_A, MP_B = 200.0, 1.6
"""Marshall-Palmer: Z = MP_A * R^MP_B."""
NO_ECHO_DBZ = 0.0
"""Reflectivity below this is no rain, dBZ."""
DBZ_UNITS = ("dBZ", "dBz", "dbz", "DBZ")
LAT_NAMES = ("lat", "latitude")
LON_NAMES = ("lon", "longitude")


def dbz_to_rate(dbz: npt.ArrayLike) -> Any:
    """The rain rate of radar reflectivity by Marshall-Palmer (the module's docstring).

    Args:
        dbz: Reflectivity, dBZ.

    Returns:
        Rain rate, mm/h.
    """
    z = np.asarray(dbz, dtype=np.float64)
    r = (10.0 ** (z / 10.0) / MP_A) ** (1.0 / MP_B)
    return np.where(z < NO_ECHO_DBZ, 0.0, r)


def _axes(path: Any, ds: Any, da: Any) -> tuple[str, str, Any]:
    """The data's horizontal dimensions (x-like, y-like) and the CRS they are in."""
    dims = [d for d in da.dims if d != "time"]
    lon = next((d for d in dims if d in LON_NAMES), None)
    lat = next((d for d in dims if d in LAT_NAMES), None)
    pyproj = pyproj_module()
    if lon and lat:
        return lon, lat, pyproj.CRS.from_epsg(4326)
    if set(dims) != {"x", "y"}:
        raise InvalidInputError(
            f"rain file {path}: {da.name} needs dimensions (time, lat, lon) or (time, y, x) "
            f"(has {da.dims})"
        )
    gm = da.attrs.get("grid_mapping")
    crs_var = ds.variables.get(gm) if gm else None
    wkt = None if crs_var is None else (
        crs_var.attrs.get("crs_wkt") or crs_var.attrs.get("spatial_ref")
    )  # fmt: skip
    if not wkt:
        raise InvalidInputError(
            f"rain file {path}: {da.name} has projected x/y but no CRS (a grid_mapping "
            "variable with crs_wkt or spatial_ref); give lat/lon coordinates or the CRS"
        )
    try:
        return "x", "y", pyproj.CRS.from_wkt(str(wkt))
    except Exception as err:  # pyproj raises CRSError and others for a bad WKT
        raise InvalidInputError(f"rain file {path}: its CRS cannot be read ({err})") from err


def read_radar_grid(
    path: str | os.PathLike[str],
    area: Area,
    georef: Georef,
    base: Medium | None = None,
    variable: str | None = None,
    max_cells: int = 201,
) -> Medium:
    """The weather of a georeferenced rain file over a scenario's area (the module's docstring).

    The base weather's rates are replaced by the file's, moving where the file has several instants.

    Args:
        path: The file: NetCDF on lat/lon or x/y with a CRS, a GeoTIFF with a band per instant, or a
            folder of GeoTIFF scans; mm/h or dBZ.
        area: The scenario's area.
        georef: Ties the area to the Earth.
        base: The weather whose rates are replaced (default: today's rain model).
        variable: The file's variable; None: the one (time, y, x) variable.
        max_cells: The most grid cells a side the file is sampled on.

    Returns:
        The [`Medium`][rainuav.radio.scene.weather.Medium].

    Raises:
        InvalidInputError: A file that cannot be read, has no such variable, units other than mm/h
            or dBZ, values not finite or outside 0-500 mm/h, or does not cover the area (the file
            named).
    """
    with open_geotiff(path) if is_geotiff(path) else _open(path) as ds:
        names = [_rain_variable(ds, variable, f"rain file {path}")]
        da = ds[names[0]]
        units = str(da.attrs.get("units", "")).strip()
        if units not in UNITS + DBZ_UNITS:
            raise InvalidInputError(
                f"rain file {path}: {names[0]}.units must be mm/h or dBZ (got {units!r})"
            )
        if "time" not in da.dims:
            raise InvalidInputError(f"rain file {path}: {names[0]} needs a time dimension")
        xd, yd, crs = _axes(path, ds, da)
        times = _seconds(path, da["time"].values)
        gx, gy = np.meshgrid(*sample_grid(area, max_cells))
        lat, lon = georef.to_latlon(gx, gy)
        to_file = pyproj_module().Transformer.from_crs("EPSG:4326", crs, always_xy=True)
        fx, fy = to_file.transform(lon, lat)
        for name, want in ((xd, fx), (yd, fy)):
            have = np.asarray(da[name].values, dtype=float)
            if not np.all(np.isfinite(have)) or have.min() > want.min() or have.max() < want.max():
                raise InvalidInputError(
                    f"rain file {path}: its {name} ({have.min():g} to {have.max():g}) must "
                    f"cover the area ({want.min():g} to {want.max():g})"
                )
        check_fits(f"rain file {path}: {names[0]} ({da.size} values)", 3 * 8 * da.size,
                   "cut the file to the area and the flight's time")  # fmt: skip
        import xarray as xr

        px = xr.DataArray(fx, dims=("py", "px"))
        py = xr.DataArray(fy, dims=("py", "px"))
        try:
            grid = da.transpose("time", yd, xd).sortby(xd).sortby(yd)
            vals = grid.interp({xd: px, yd: py}).transpose("time", "py", "px").values
        except Exception as err:  # the data itself could not be read
            raise InvalidInputError(f"rain file {path}: {names[0]} cannot be read ({err})") from err
    if not np.all(np.isfinite(vals)):
        raise InvalidInputError(f"rain file {path}: {names[0]} must be finite over the area")
    rates = dbz_to_rate(vals) if units in DBZ_UNITS else vals
    if rates.min() < 0 or rates.max() > MAX_RATE_MM_H:
        raise InvalidInputError(
            f"rain file {path}: {names[0]} gives rain outside 0..{MAX_RATE_MM_H:g} mm/h"
        )
    return rate_medium(base, rates, times)
