"""Rain from GeoTIFF files, as many radar archives and GIS exports deliver it,
read with rasterio (GDAL) into the same CF form as a NetCDF rain file, so one reader
([`rainuav.radio.scene.radar.read_radar_grid()`][rainuav.radio.scene.radar.read_radar_grid])
reprojects both.

- **One file, one band per instant**, or **a folder of such files** (``*.tif``, ``*.tiff``;
  one per scan, as archives keep them), all on the same grid.
- **The instant of each band**: its description as an ISO 8601 date
  (``2026-06-01T14:00:00``, what ``gdal_edit.py`` / rasterio's ``set_band_description``
  write), else its ``time`` tag, else, for a one-band file, the file's ``TIFFTAG_DATETIME``
  (``2026:06:01 14:00:00``). A band without one is refused: the weather's motion would be a
  guess.
- **Units**: the band's unit (``units``, GDAL's band unit type) or its ``units`` tag, else the
  file's ``units`` tag: ``mm/h`` or ``dBZ``
  ([`rainuav.radio.scene.radar`][rainuav.radio.scene.radar] converts dBZ).
- **Georeference**: the file's CRS and its affine transform (north-up grids only: a rotated
  transform is refused); pixel centres become the ``x``/``y`` coordinates. The file's nodata
  value reads as missing (the area must then avoid it).

Needs the ``geo`` extra (pyproj, rasterio).
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import numpy as np

from rainuav._checks import check_fits
from rainuav.errors import InvalidInputError

__all__ = ["SUFFIXES", "is_geotiff", "open_geotiff"]

SUFFIXES = (".tif", ".tiff")
"""File names read as GeoTIFF."""


def is_geotiff(path: str | os.PathLike[str]) -> bool:
    """Whether a path is read as GeoTIFF: a `.tif` / `.tiff` file, or a folder.

    Args:
        path: The path.

    Returns:
        True for GeoTIFF.
    """
    p = Path(path)
    return p.is_dir() or p.suffix.lower() in SUFFIXES


def _rasterio(path: Any) -> Any:
    try:
        import rasterio
    except ImportError as err:
        raise InvalidInputError(
            f"rain file {path}: reading GeoTIFF needs rasterio: pip install '.[geo]' from "
            "the rainuav clone"
        ) from err
    return rasterio


def _instant(path: Any, band: int, text: str) -> np.datetime64:
    text = text.strip()
    if len(text) >= 19 and text[4] == ":" and text[7] == ":":  # TIFFTAG_DATETIME
        text = text[:4] + "-" + text[5:7] + "-" + text[8:10] + "T" + text[11:19]
    try:
        return np.datetime64(text.rstrip("Z"), "s")
    except ValueError as err:
        raise InvalidInputError(
            f"rain file {path}: band {band}'s time {text!r} is not an ISO 8601 date"
        ) from err


def _bands(path: Path) -> tuple[np.ndarray, list[np.datetime64], str, Any, Any]:
    """(values (B, H, W), instants, units, CRS, transform) of one GeoTIFF."""
    rasterio = _rasterio(path)
    try:
        src = rasterio.open(path)
    except Exception as err:  # rasterio raises RasterioIOError and others
        why = str(err).strip().splitlines()[0] if str(err).strip() else type(err).__name__
        raise InvalidInputError(f"rain file {path}: not a readable GeoTIFF ({why})") from err
    with src:
        if src.crs is None:
            raise InvalidInputError(
                f"rain file {path}: has no CRS; write it with its coordinate reference system"
            )
        t = src.transform
        if t.b != 0 or t.d != 0 or t.a <= 0 or t.e >= 0:
            raise InvalidInputError(
                f"rain file {path}: its grid must be north-up (a rotated or flipped transform "
                f"is not read; got {tuple(t)[:6]})"
            )
        file_tags = src.tags()
        times, units = [], set()
        for b in range(1, src.count + 1):
            tags = src.tags(b)
            when = src.descriptions[b - 1] or tags.get("time")
            if not when and src.count == 1:
                when = file_tags.get("TIFFTAG_DATETIME")
            if not when:
                raise InvalidInputError(
                    f"rain file {path}: band {b} has no time (its description, a 'time' tag "
                    "or, for one band, TIFFTAG_DATETIME)"
                )
            times.append(_instant(path, b, str(when)))
            units.add(src.units[b - 1] or tags.get("units") or file_tags.get("units") or "")
        if len(units) != 1:
            raise InvalidInputError(f"rain file {path}: its bands have different units {units}")
        size = src.count * src.height * src.width
        check_fits(f"rain file {path} ({src.count} bands of {src.height} x {src.width})",
                   3 * 8 * size, "cut the file to the area and the flight's time")  # fmt: skip
        values = src.read(masked=True).astype(np.float64).filled(np.nan)
        return values, times, units.pop(), src.crs, t


def open_geotiff(path: str | os.PathLike[str]) -> Any:
    """A GeoTIFF file or folder as an xarray Dataset in CF form (the module's docstring).

    `rain` (time, y, x) with its `units`, a `grid_mapping` variable `crs` holding the CRS as WKT,
    `x` / `y` the pixel centres, `time` the instants, sorted.

    Args:
        path: A file, or a folder of scans.

    Returns:
        The Dataset.

    Raises:
        InvalidInputError: No such file, a folder without GeoTIFF files, or files whose grid, CRS or
            units differ.
    """
    import xarray as xr

    p = Path(path)
    if p.is_dir():
        files = sorted(f for f in p.iterdir() if f.suffix.lower() in SUFFIXES)
        if not files:
            raise InvalidInputError(f"rain folder {path}: holds no .tif or .tiff file")
    elif p.is_file():
        files = [p]
    else:
        raise InvalidInputError(f"rain file {path}: no such file")
    parts = [_bands(f) for f in files]
    values, _, units, crs, t = parts[0]
    for f, (v, _, u, c, tr) in zip(files[1:], parts[1:], strict=True):
        if v.shape[1:] != values.shape[1:] or c != crs or tr != t or u != units:
            raise InvalidInputError(
                f"rain file {f}: its grid, CRS or units differ from {files[0].name}'s"
            )
    values = np.concatenate([v for v, *_ in parts])
    when = np.array([w for _, ts, *_ in parts for w in ts], dtype="datetime64[s]")
    order = np.argsort(when, kind="stable")
    h, w = values.shape[1:]
    x = t.c + t.a * (np.arange(w) + 0.5)
    y = t.f + t.e * (np.arange(h) + 0.5)
    rain = xr.DataArray(
        values[order],
        dims=("time", "y", "x"),
        coords={"time": when[order], "y": y, "x": x},
        name="rain",
        attrs={"units": units, "grid_mapping": "crs"},
    )
    crs_var = xr.DataArray(0, attrs={"crs_wkt": crs.to_wkt()})
    return xr.Dataset({"rain": rain, "crs": crs_var})
