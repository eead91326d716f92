"""Terrain from a digital elevation model: a GeoTIFF in any CRS, as SRTM and Copernicus GLO-30
deliver it (EPSG:4326, metres above the geoid, int16 or float32, a nodata value), read with
rasterio (GDAL) and pyproj onto the nodes of a scenario's area.

**How it is resampled.** The area's nodes (a regular grid at most 10 m apart that holds every pixel
corner) are projected into the DEM's CRS (local metres -> latitude and longitude through the
scenario's [`rainuav.geo.Georef`][rainuav.geo.Georef] -> the DEM's CRS) and read **bilinearly
between the DEM's cell centres** (GDAL's convention: a value belongs to its cell's centre). Between
the nodes the ray engine is bilinear again (``rainuav_core::propagation::rays::Raster``). Only the
window of the file over the area is read, and its memory is checked before reading, so a
continent-sized file costs what the area costs.

**Refused, in one line naming the file:** a file that is not a raster; no CRS; a rotated or flipped
transform; a band unit that is not metres (where the file states one); the area not inside the file;
nodata on a cell the area reads; heights outside
[`HEIGHT_RANGE_M`][rainuav.ground.dem.HEIGHT_RANGE_M]; a window too big for the memory.

Needs the ``geo`` extra (pyproj, rasterio).
"""

from __future__ import annotations

import functools
import hashlib
import math
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from rainuav._checks import check_fits
from rainuav.errors import InvalidInputError
from rainuav.geo import Georef, pyproj_module

__all__ = [
    "HEIGHT_RANGE_M",
    "MAX_NODE_SPACING_M",
    "Terrain",
    "file_digest",
    "open_raster",
    "read_dem",
    "terrain_nodes",
]

HEIGHT_RANGE_M = (-500.0, 9000.0)
"""Terrain heights accepted, m above sea level (the Dead Sea shore to above Everest)."""

MAX_NODE_SPACING_M = 10.0
"""The terrain's nodes over the area are at most this far apart (and hold every pixel corner)."""

_METRES = {"m", "metre", "metres", "meter", "meters", "metre(s)"}


def open_raster(path: str | os.PathLike[str], what: str) -> Any:
    """A raster opened with rasterio, checked to have a CRS and a north-up grid (the caller closes
    it).

    Args:
        path: The GeoTIFF.
        what: What the errors call it ("DEM file", "rain file").

    Returns:
        The rasterio dataset.

    Raises:
        InvalidInputError: No such file, rasterio not installed, a file it cannot read, no CRS, or a
            grid that is not north-up (named).
    """
    try:
        import rasterio
    except ImportError as err:
        raise InvalidInputError(
            f"{what} {path}: reading GeoTIFF needs rasterio: pip install '.[geo]' from the "
            "rainuav clone"
        ) from err
    if not Path(path).is_file():
        raise InvalidInputError(f"{what} {path}: no such file")
    try:
        src = rasterio.open(path)
    except Exception as err:  # rasterio raises RasterioIOError and others
        why = str(err).strip().splitlines()[0] if str(err).strip() else type(err).__name__
        raise InvalidInputError(f"{what} {path}: not a readable GeoTIFF ({why})") from err
    if src.crs is None:
        src.close()
        raise InvalidInputError(
            f"{what} {path}: has no CRS; write it with its coordinate reference system"
        )
    t = src.transform
    if t.b != 0 or t.d != 0 or t.a <= 0 or t.e >= 0:
        src.close()
        raise InvalidInputError(
            f"{what} {path}: its grid must be north-up (a rotated or flipped transform "
            f"is not read; got {tuple(t)[:6]})"
        )
    return src


def file_digest(path: str | os.PathLike[str]) -> str:
    """The SHA-256 of a file's contents: the radio-map cache keys on it.

    The file is hashed once per version (its path, size and modification time), however often a map
    build asks.

    Args:
        path: The file.

    Returns:
        The digest, as hexadecimal text.
    """
    st = os.stat(path)
    return _digest(os.path.realpath(path), st.st_size, st.st_mtime_ns)


@functools.lru_cache(maxsize=32)
def _digest(path: str, size: int, mtime_ns: int) -> str:
    del size, mtime_ns  # in the key only: a changed file is hashed again
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def terrain_nodes(
    bounds: tuple[float, float, float, float], shape: tuple[int, int]
) -> tuple[np.ndarray, np.ndarray]:
    """The nodes the terrain is sampled on for a map.

    The same whole number of nodes per pixel each way, at most
    [`MAX_NODE_SPACING_M`][rainuav.ground.dem.MAX_NODE_SPACING_M] apart, every pixel corner among
    them.

    Args:
        bounds: The area, `(x_min, x_max, y_min, y_max)`, m.
        shape: The map's (H, W) pixels.

    Returns:
        `(east, north)`: the nodes' coordinates (nx,) and (ny,), m.
    """
    x0, x1, y0, y1 = bounds
    hh, ww = shape
    k = max(1, math.ceil(max((x1 - x0) / ww, (y1 - y0) / hh) / MAX_NODE_SPACING_M - 1e-9))
    xs = x0 + (x1 - x0) * np.arange(ww * k + 1) / (ww * k)
    ys = y0 + (y1 - y0) * np.arange(hh * k + 1) / (hh * k)
    return xs, ys


@dataclass(frozen=True)
class Terrain:
    """Terrain heights above sea level (m) at the nodes of an area: ``heights_m[i, j]`` at
    ``(x0_m + j step_m, y0_m + i step_m)`` (rows south to north)."""

    heights_m: np.ndarray
    """(ny, nx) heights, m above sea level."""
    x0_m: float
    """East coordinate of the first column, m."""
    dx_m: float
    """Node spacing east, m."""
    y0_m: float
    """North coordinate of the first row, m."""
    dy_m: float
    """Node spacing north, m."""
    source: str
    """Where the heights came from (a file name, or a description)."""

    @property
    def origin_step(self) -> tuple[float, float, float, float]:
        """``(x0, dx, y0, dy)`` as the core's rasters take them."""
        return (self.x0_m, self.dx_m, self.y0_m, self.dy_m)

    def at(self, x: npt.ArrayLike, y: npt.ArrayLike) -> np.ndarray:
        """Terrain heights at points, bilinear between nodes, held beyond the outermost (the core's
        reading).

        Args:
            x: East, m (any shape).
            y: North, m (broadcastable with `x`).

        Returns:
            Heights, m.
        """
        h = self.heights_m
        fx = np.clip((np.asarray(x, float) - self.x0_m) / self.dx_m, 0, h.shape[1] - 1)
        fy = np.clip((np.asarray(y, float) - self.y0_m) / self.dy_m, 0, h.shape[0] - 1)
        j = np.minimum(np.floor(fx).astype(int), max(h.shape[1] - 2, 0))
        i = np.minimum(np.floor(fy).astype(int), max(h.shape[0] - 2, 0))
        tx, ty = fx - j, fy - i
        j1, i1 = np.minimum(j + 1, h.shape[1] - 1), np.minimum(i + 1, h.shape[0] - 1)
        return (
            h[i, j] * (1 - tx) * (1 - ty)
            + h[i, j1] * tx * (1 - ty)
            + h[i1, j] * (1 - tx) * ty
            + h[i1, j1] * tx * ty
        )

    def pixel_max(self, shape: tuple[int, int]) -> np.ndarray:
        """The highest terrain within each pixel of the map these nodes are for.

        The largest node on the pixel's closed square (bilinear between nodes has its extremes at
        nodes).

        Args:
            shape: The map's (H, W) ([`terrain_nodes()`][rainuav.ground.dem.terrain_nodes] gave the
                nodes of it).

        Returns:
            (H, W) heights, m.

        Raises:
            ValueError: Nodes that are not those of a map of `shape`.
        """
        hh, ww = shape
        h = self.heights_m
        k = (h.shape[1] - 1) // ww
        if (h.shape[0] - 1) != k * hh or (h.shape[1] - 1) != k * ww:
            raise ValueError(f"terrain nodes {h.shape} are not those of a {shape} map")
        out = np.full((hh, ww), -np.inf)
        for a in range(k + 1):
            for b in range(k + 1):
                out = np.maximum(out, h[a : a + k * hh : k, b : b + k * ww : k])
        return out


def _vertical_unit(src: Any) -> str | None:
    unit = (src.units[0] if src.units else "") or src.tags(1).get("units") or ""
    unit = unit.strip().lower()
    return unit or None


def read_dem(
    path: str | os.PathLike[str],
    georef: Georef,
    bounds: tuple[float, float, float, float],
    shape: tuple[int, int],
) -> Terrain:
    """The terrain of a DEM GeoTIFF on the nodes of a map's area.

    The module's docstring says how the DEM is resampled and what is refused.

    Args:
        path: The GeoTIFF.
        georef: The scenario's local frame ([`Georef`][rainuav.geo.Georef]).
        bounds: The area, `(x_min, x_max, y_min, y_max)` in metres of the local frame.
        shape: The map's (H, W) pixels.

    Returns:
        The [`Terrain`][rainuav.ground.dem.Terrain] on
        [`terrain_nodes()`][rainuav.ground.dem.terrain_nodes] of the area.

    Raises:
        InvalidInputError: A file that cannot be read, does not cover the area, has no data over it,
            heights not in metres or out of range, or an area its CRS cannot hold (the file named).
    """
    from rasterio.windows import Window
    from scipy.ndimage import map_coordinates

    what = "DEM file"
    xs, ys = terrain_nodes(bounds, shape)
    gx, gy = np.meshgrid(xs, ys)
    lat, lon = georef.to_latlon(gx, gy)
    with open_raster(path, what) as src:
        unit = _vertical_unit(src)
        if unit is not None and unit not in _METRES:
            raise InvalidInputError(
                f"{what} {path}: its heights are in {unit!r}; rainuav reads metres "
                "(convert the file, e.g. gdal_calc.py, and set its unit to 'm')"
            )
        pyproj = pyproj_module()
        to_dem = pyproj.Transformer.from_crs("EPSG:4326", src.crs, always_xy=True)
        ex, ey = to_dem.transform(lon, lat)
        t = src.transform
        # Fractional (row, column) of each node between cell centres.
        col = (np.asarray(ex) - t.c) / t.a - 0.5
        row = (np.asarray(ey) - t.f) / t.e - 0.5
        if not (np.all(np.isfinite(col)) and np.all(np.isfinite(row))):
            raise InvalidInputError(f"{what} {path}: the area cannot be projected into its CRS")
        lo_c, hi_c, lo_r, hi_r = col.min(), col.max(), row.min(), row.max()
        if lo_c < -0.5 or lo_r < -0.5 or hi_c > src.width - 0.5 or hi_r > src.height - 0.5:
            raise InvalidInputError(
                f"{what} {path}: does not cover the area (the area needs columns "
                f"{lo_c:.1f}..{hi_c:.1f} and rows {lo_r:.1f}..{hi_r:.1f} of its "
                f"{src.width} x {src.height} cells)"
            )
        c0 = max(0, math.floor(lo_c))
        r0 = max(0, math.floor(lo_r))
        c1 = min(src.width - 1, math.ceil(hi_c))
        r1 = min(src.height - 1, math.ceil(hi_r))
        rows, cols = r1 - r0 + 1, c1 - c0 + 1
        check_fits(f"{what} {path} (a window of {rows} x {cols} cells over the area)",
                   3 * 8 * rows * cols, "use a coarser DEM or a smaller area")  # fmt: skip
        win = src.read(1, window=Window(c0, r0, cols, rows), masked=True)
    values = np.ma.filled(win.astype(np.float64), np.nan)
    coords = np.stack([np.clip(row - r0, 0, rows - 1), np.clip(col - c0, 0, cols - 1)])
    # A node reads the four cells around it: any of them missing is nodata over the area.
    missing = map_coordinates(np.isnan(values).astype(float), coords, order=1, mode="nearest")
    if np.any(missing > 0):
        raise InvalidInputError(
            f"{what} {path}: has nodata over the area ({int(np.sum(missing > 0))} of "
            f"{missing.size} terrain nodes); fill the voids first (e.g. gdal_fillnodata.py)"
        )
    heights = map_coordinates(values, coords, order=1, mode="nearest")
    lo, hi = HEIGHT_RANGE_M
    if not (np.all(np.isfinite(heights)) and heights.min() >= lo and heights.max() <= hi):
        raise InvalidInputError(
            f"{what} {path}: heights {np.nanmin(heights):.1f}..{np.nanmax(heights):.1f} m over "
            f"the area; they must be within {lo:g}..{hi:g} m above sea level"
        )
    return Terrain(
        heights_m=np.ascontiguousarray(heights),
        x0_m=float(xs[0]),
        dx_m=float(xs[1] - xs[0]),
        y0_m=float(ys[0]),
        dy_m=float(ys[1] - ys[0]),
        source=Path(path).name,
    )
