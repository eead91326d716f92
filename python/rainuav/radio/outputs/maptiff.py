"""Radio maps out as GeoTIFF, as GIS tools (QGIS, GDAL) read them.

One file, four to six float32 bands over the map's pixels, north-up, in the scenario's own
projection (its [`rainuav.geo.Georef`][rainuav.geo.Georef]: an azimuthal equidistant projection
on WGS 84 centred on the origin, written as the file's CRS), with band descriptions and units:

1. ``sinr_db``: SINR, dB;
2. ``rss_serving_dbm``: the received power of the serving cell, dBm;
3. ``serving_cell``: the index of the serving cell (nodata where no cell reaches);
4. ``not_flyable``: 1 where the UAV may not fly (terrain or obstacles within the clearance
   of the flight height), else 0;
5. ``rss_serving_std_db`` (a map that carries its spreads: a map corrected by measurements,
   [`rainuav.radio.measured`][rainuav.radio.measured], or a physics map written by
   ``radiomap`` with its prior's): the standard deviation of band 2's local mean, dB;
6. ``rss_serving_sample_std_db`` (the same maps): one sample's around it, dB.

The nodata value is [`NODATA`][rainuav.radio.outputs.maptiff.NODATA]. Written to a temporary file
and renamed: a reader never sees half a file. Needs rasterio (the ``geo`` extra)."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import numpy as np

from rainuav._io import write_atomic
from rainuav.errors import InvalidInputError

__all__ = ["BANDS", "NODATA", "write_map_geotiff"]

NODATA = -9999.0
"""The files' nodata value."""

BANDS = (
    ("sinr_db", "dB"),
    ("rss_serving_dbm", "dBm"),
    ("serving_cell", ""),
    ("not_flyable", ""),
)
"""Band names (descriptions) and units, in order."""
STD_BAND = ("rss_serving_std_db", "dB")
"""The fifth band of a map that carries its spreads: the serving cell's local-mean spread."""
SAMPLE_BAND = ("rss_serving_sample_std_db", "dB")
"""The sixth band of a map that carries its spreads: one sample's spread around it."""


def _bands(rm: Any, slice_index: int | None) -> np.ndarray:
    """(4, H, W) float32 (5 or 6 for a corrected map), rows south to north (the map's own
    order)."""
    sinr, rss, serving = rm.sinr_db, rm.rss_dbm, rm.serving_cell
    if slice_index is not None:  # a map in time: one instant (read before the whole series)
        sinr, rss, serving = sinr[slice_index], rss[slice_index], serving[slice_index]
    sinr = np.asarray(sinr, dtype=np.float64)
    rss = np.asarray(rss, dtype=np.float64)
    serving = np.asarray(serving)
    h, w = sinr.shape
    ii, jj = np.indices((h, w))
    best = np.where(serving >= 0, rss[np.maximum(serving, 0), ii, jj], NODATA)
    mask = getattr(rm, "not_flyable", None)
    if mask is None:
        from rainuav.radio.scene.terrain import map_mask

        mask = map_mask(rm.scenario)
    blocked = np.zeros((h, w)) if mask is None else np.asarray(mask, dtype=np.float64)
    cell = np.where(serving >= 0, serving, NODATA)
    bands = [sinr, best, cell, blocked]
    std = getattr(rm, "rss_std_db", None)
    if std is not None and slice_index is None:
        bands.append(np.where(serving >= 0, std[np.maximum(serving, 0), ii, jj], NODATA))
        one = getattr(rm, "rss_sample_std_db", None)
        if one is not None:
            bands.append(np.where(serving >= 0, one[np.maximum(serving, 0), ii, jj], NODATA))
    return np.stack(bands).astype(np.float32)


def write_map_geotiff(
    rm: Any, path: str | os.PathLike[str], slice_index: int | None = None
) -> Path:
    """Writes a map of a georeferenced scenario as GeoTIFF (the module's docstring), atomically.

    Args:
        rm: A [`RadioMap`][rainuav.radio.outputs.mapdata.RadioMap], or a map series.
        path: The file.
        slice_index: The instant of a series written; None for a map.

    Returns:
        The path written.

    Raises:
        InvalidInputError: rasterio is not installed, or the scenario has no `[origin]`.
    """
    try:
        import rasterio
        from rasterio.transform import Affine
    except ImportError as err:
        raise InvalidInputError(
            "writing GeoTIFF needs rasterio: pip install '.[geo]' from the rainuav clone"
        ) from err
    scn = rm.scenario
    geo = scn.georef
    if geo is None:
        raise InvalidInputError(
            "a GeoTIFF needs a georeferenced scenario ([origin] with lat_deg and lon_deg)"
        )
    a = scn.area
    data = _bands(rm, slice_index)[:, ::-1, :]  # rows north to south
    count, h, w = data.shape
    names = (*BANDS, STD_BAND, SAMPLE_BAND)[:count]
    px, py = (a.x_max_m - a.x_min_m) / w, (a.y_max_m - a.y_min_m) / h
    profile = {
        "driver": "GTiff", "height": h, "width": w, "count": count, "dtype": "float32",
        "crs": rasterio.crs.CRS.from_proj4(geo.proj4), "nodata": NODATA,
        "transform": Affine(px, 0.0, a.x_min_m, 0.0, -py, a.y_max_m), "compress": "deflate",
    }  # fmt: skip

    def write(tmp: Path) -> None:
        with rasterio.open(tmp, "w", **profile) as dst:
            dst.write(np.ascontiguousarray(data))
            for k, (name, unit) in enumerate(names, start=1):
                dst.set_band_description(k, name)
                if unit:
                    dst.set_band_unit(k, unit)
            dst.update_tags(scenario=scn.name, altitude_m=str(a.altitude_m),
                            altitude_reference=a.altitude_reference or "ground")  # fmt: skip

    return write_atomic(path, write)
