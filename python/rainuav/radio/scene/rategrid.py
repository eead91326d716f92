"""Rain from a file: a NetCDF dataset of rain rates on (time, y, x) in the scenario's metres, read
with xarray into a moving weather
([`rainuav.radio.scene.weather.Medium`][rainuav.radio.scene.weather.Medium] of kind ``'map'`` with
one map per instant; ``medium.at(t)`` interpolates linearly in time, exact at the file's own
instants). Georeferenced grids (latitude/longitude, a CRS, dBZ) are read by
[`rainuav.radio.scene.radar`][rainuav.radio.scene.radar].

The file holds one data variable with dimensions ``(time, y, x)`` (or the one named by
``variable``) in ``mm/h`` (``units`` attribute: ``mm/h``, ``mm h-1``, ``mm hr-1`` or
``mm/hr``), coordinates ``x`` and ``y`` in metres (a regular or irregular grid that covers the
area) and ``time`` in seconds (numbers) or as datetimes (taken from the first). The rates are
interpolated bilinearly (xarray's ``interp``) onto the centres of a grid over the area, at most
``max_cells`` a side, and must be finite, within 0..500 mm/h.

Needs the optional ``weather`` extra (``pip install '.[weather]' from the rainuav clone``: xarray
and h5netcdf, so that both NetCDF-3 and NetCDF-4 files open)."""

from __future__ import annotations

import dataclasses
import os
from typing import Any

import numpy as np

from rainuav._checks import check_fits
from rainuav.errors import InvalidInputError
from rainuav.radio.scene.scenario import Area
from rainuav.radio.scene.weather import MAX_RATE_MM_H, Medium

__all__ = ["UNITS", "rate_medium", "read_rate_grid", "sample_grid"]

UNITS = ("mm/h", "mm h-1", "mm hr-1", "mm/hr", "mm h**-1")
"""Spellings of millimetres per hour accepted in a file's ``units`` attribute."""


def _open(path: str | os.PathLike[str]) -> Any:
    try:
        import xarray as xr
    except ImportError as err:
        raise InvalidInputError(
            "reading rain-rate files needs xarray: pip install '.[weather]' from the rainuav clone"
        ) from err
    if not os.path.isfile(path):
        raise InvalidInputError(f"rain-rate file {path}: no such file")
    try:
        return xr.open_dataset(path)  # lazily: nothing is read before the sizes are checked
    except Exception as err:  # xarray raises many kinds for a file it cannot read
        why = str(err).strip().splitlines()[0] if str(err).strip() else type(err).__name__
        raise InvalidInputError(
            f"rain-rate file {path}: not a readable NetCDF file ({why})"
        ) from err


def _seconds(path: Any, time: Any) -> np.ndarray:
    t = np.asarray(time)
    if np.issubdtype(t.dtype, np.datetime64):
        t = (t - t[0]) / np.timedelta64(1, "s")
    elif np.issubdtype(t.dtype, np.timedelta64):
        t = t / np.timedelta64(1, "s")
    try:
        t = t.astype(float)
    except (TypeError, ValueError) as err:
        raise InvalidInputError(f"rain-rate file {path}: time must be seconds or dates") from err
    if t.ndim != 1 or not np.all(np.isfinite(t)) or np.any(np.diff(t) <= 0):
        raise InvalidInputError(f"rain-rate file {path}: time must be strictly increasing")
    return t


def read_rate_grid(
    path: str | os.PathLike[str],
    area: Area,
    base: Medium | None = None,
    variable: str | None = None,
    max_cells: int = 201,
) -> Medium:
    """The moving weather of a NetCDF rain-rate file over an area (the module's docstring).

    Args:
        path: The file: (time, y, x) in mm/h on the area's metres.
        area: The scenario's area.
        base: The weather whose rates are replaced (default: today's rain model at 20 C, no wind).
        variable: The file's variable; None: the one (time, y, x) variable.
        max_cells: The most grid cells a side the file is sampled on.

    Returns:
        The [`Medium`][rainuav.radio.scene.weather.Medium].

    Raises:
        InvalidInputError: Anything the file lacks or gets wrong (the file and the field named).
    """
    with _open(path) as ds:
        return _read(path, ds, area, base, variable, max_cells)


def _rain_variable(ds: Any, variable: str | None, what: str) -> str:
    """The rain variable of a dataset: ``variable``, else its one three-dimensional variable;
    else one line naming ``what`` (the file) and the variables it has."""
    names = [variable] if variable else [k for k, v in ds.data_vars.items() if v.ndim == 3]
    if len(names) != 1 or names[0] not in ds.data_vars:
        raise InvalidInputError(
            f"{what}: needs one (time, y, x) variable, or variable= naming it "
            f"(has {sorted(ds.data_vars)})"
        )
    return names[0]


def _read(
    path: Any, ds: Any, area: Area, base: Medium | None, variable: str | None, max_cells: int
) -> Medium:
    names = [_rain_variable(ds, variable, f"rain-rate file {path}")]
    da = ds[names[0]]
    if set(da.dims) != {"time", "y", "x"}:
        raise InvalidInputError(
            f"rain-rate file {path}: {names[0]} must have dimensions (time, y, x) (has {da.dims})"
        )
    units = str(da.attrs.get("units", "")).strip()
    if units not in UNITS:
        raise InvalidInputError(
            f"rain-rate file {path}: {names[0]}.units must be mm/h (one of {UNITS}; got "
            f"{units!r}; radar reflectivity in dBZ is read by python -m rainuav.fly --weather)"
        )
    times = _seconds(path, da["time"].values)
    xs, ys = sample_grid(area, max_cells)
    for name, want in (("x", xs), ("y", ys)):
        have = np.asarray(da[name].values, dtype=float)
        if not np.all(np.isfinite(have)) or have.min() > want[0] or have.max() < want[-1]:
            raise InvalidInputError(
                f"rain-rate file {path}: {name} (m) must cover the area, {want[0]:g} to "
                f"{want[-1]:g} (has {have.min():g} to {have.max():g})"
            )
    check_fits(
        f"rain-rate file {path}: {names[0]} ({da.size} values)",
        3 * 8 * da.size,
        "cut the file to the area and the flight's time",
    )
    try:
        rates = da.transpose("time", "y", "x").sortby("x").sortby("y").interp(x=xs, y=ys).values
    except Exception as err:  # the data itself could not be read
        raise InvalidInputError(
            f"rain-rate file {path}: {names[0]} cannot be read ({err})"
        ) from err
    if not np.all(np.isfinite(rates)) or rates.min() < 0 or rates.max() > MAX_RATE_MM_H:
        raise InvalidInputError(
            f"rain-rate file {path}: {names[0]} must be finite, within 0..{MAX_RATE_MM_H:g} mm/h"
        )
    return rate_medium(base, rates, times)


def sample_grid(area: Area, max_cells: int) -> tuple[np.ndarray, np.ndarray]:
    """The centres of the grid a rain file is sampled on over an area.

    At most `max_cells` a side, square cells, never finer than the map's pixels.

    Args:
        area: The scenario's area.
        max_cells: The most cells a side.

    Returns:
        `(x (nx,), y (ny,))`, m.
    """
    x_c, y_c = area.centres()
    step = max((area.x_max_m - area.x_min_m) / max_cells, (area.y_max_m - area.y_min_m) / max_cells)
    nx = max(1, min(len(x_c), round((area.x_max_m - area.x_min_m) / step)))
    ny = max(1, min(len(y_c), round((area.y_max_m - area.y_min_m) / step)))
    xs = area.x_min_m + (np.arange(nx) + 0.5) * (area.x_max_m - area.x_min_m) / nx
    ys = area.y_min_m + (np.arange(ny) + 0.5) * (area.y_max_m - area.y_min_m) / ny
    return xs, ys


def rate_medium(base: Medium | None, rates: np.ndarray, times: np.ndarray) -> Medium:
    """A weather whose rates are a grid of rain rates in time.

    Args:
        base: The weather whose rates are replaced (default: today's rain model).
        rates: The rates (T, ny, nx), mm/h, over the area.
        times: Their instants (T,), s (T = 1: a weather that stands still).

    Returns:
        The [`Medium`][rainuav.radio.scene.weather.Medium].
    """
    one = len(times) == 1
    medium = dataclasses.replace(
        base or Medium(),
        kind="map",
        cells=[],
        rate_map_mm_h=(rates[0] if one else rates).tolist(),
        rate_times_s=None if one else [float(v) for v in times],
    )
    medium.check()
    return medium
