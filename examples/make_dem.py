"""Writes ``examples/dem.tif``: a digital elevation model in the form SRTM delivers it
(GeoTIFF, EPSG:4326, one arc-second cells, int16 metres above the geoid, nodata -32768), for
``python -m rainuav.fly --terrain examples/dem.tif``.

Synthetic heights over the shipped place (Zurich, the sites of ``examples/sites.csv``): a
410 m plain and a rounded ridge 140 m high and about 2 km long running north-south at 8.546 E,
between site ZH-001 (8.535 E) and the eastern part of the area, rising to a 190 m knoll near its
northern end.
Not Zurich's real terrain: an example that shows what a ridge does.

    python examples/make_dem.py
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

CELL = 1.0 / 3600.0  # one arc-second, as SRTM 1 and Copernicus GLO-30
NORTH, WEST, SOUTH, EAST = 47.395, 8.520, 47.350, 8.575
M_PER_DEG_LAT, M_PER_DEG_LON = 111_200.0, 75_400.0  # near 47.37 N


def heights(lat: np.ndarray, lon: np.ndarray) -> np.ndarray:
    """The example's terrain, m above the geoid."""
    x = (lon - 8.546) * M_PER_DEG_LON
    y = (lat - 47.372) * M_PER_DEG_LAT
    ridge = 140.0 * np.exp(-((x / 160.0) ** 2)) * np.exp(-((y / 1000.0) ** 4))
    knoll = 50.0 * np.exp(-((x / 160.0) ** 2 + ((y - 700.0) / 250.0) ** 2))
    return 410.0 + ridge + knoll


def main() -> Path:
    import rasterio
    from rasterio.transform import Affine

    rows = round((NORTH - SOUTH) / CELL)
    cols = round((EAST - WEST) / CELL)
    lat = NORTH - (np.arange(rows) + 0.5) * CELL
    lon = WEST + (np.arange(cols) + 0.5) * CELL
    z = np.round(heights(lat[:, None], lon[None, :])).astype(np.int16)
    out = Path(__file__).resolve().parent / "dem.tif"
    profile = {
        "driver": "GTiff", "height": rows, "width": cols, "count": 1, "dtype": "int16",
        "crs": "EPSG:4326", "transform": Affine(CELL, 0.0, WEST, 0.0, -CELL, NORTH),
        "nodata": -32768, "compress": "deflate",
    }  # fmt: skip
    with rasterio.open(out, "w", **profile) as dst:
        dst.write(z, 1)
        dst.units = ("m",)
        dst.set_band_description(1, "height above the geoid")
    return out


if __name__ == "__main__":
    print(f"wrote {main()}")
